# npm packages pinned by a lock file, installed at build time into the build tree (never at run
# time: the machine may be offline then).
#
#   dpc_npm_ci(<target> <source dir with package.json + package-lock.json> <output dir> <comment>)
# makes <target> (built by `all`) run `npm ci` in <output dir> whenever the package files change,
# and sets <target>_MODULES in the caller's scope to <output dir>/node_modules and
# <target>_STAMP to the file that marks them installed.
function(dpc_npm_ci target source_dir output_dir comment)
  set(stamp ${output_dir}/node_modules/.package-lock.json)
  file(MAKE_DIRECTORY ${output_dir})
  add_custom_command(OUTPUT ${stamp}
    COMMAND ${CMAKE_COMMAND} -E copy ${source_dir}/package.json ${source_dir}/package-lock.json ${output_dir}
    COMMAND ${DPC_NPM} ci --ignore-scripts --no-audit --no-fund --loglevel=error
    COMMAND ${CMAKE_COMMAND} -E touch ${stamp}
    WORKING_DIRECTORY ${output_dir}
    DEPENDS ${source_dir}/package.json ${source_dir}/package-lock.json
    COMMENT "npm ci: ${comment} (pinned in package-lock.json)"
    VERBATIM)
  add_custom_target(${target} ALL DEPENDS ${stamp})
  set(${target}_MODULES ${output_dir}/node_modules PARENT_SCOPE)
  set(${target}_STAMP ${stamp} PARENT_SCOPE)
endfunction()
