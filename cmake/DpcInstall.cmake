# `cmake --install`: the binaries, the Fast DDS profiles, the scenarios, the IDL, the security
# script, bash completion for dpc, the dashboard's page (tools/dpc), and the core library with
# its headers as a CMake package: find_package(jacobian_dpc) → jacobian_dpc::core
# (tests/install builds a consumer project against it).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(DPC_CORE_MODULES optics control config disturbance sim)
add_library(dpc_core INTERFACE)
set_target_properties(dpc_core PROPERTIES EXPORT_NAME core)
foreach(module IN LISTS DPC_CORE_MODULES)
  set_target_properties(dpc_${module} PROPERTIES EXPORT_NAME ${module})
  target_link_libraries(dpc_core INTERFACE dpc_${module})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/common/dpc/${module}
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/dpc FILES_MATCHING PATTERN "*.h")
endforeach()
list(TRANSFORM DPC_CORE_MODULES PREPEND dpc_ OUTPUT_VARIABLE dpc_core_targets)
# Eigen's fixed-size types are laid out for the instruction set they are compiled for (AVX: 32-byte
# alignment, AVX-512: 64-byte): code that includes these headers must be compiled as the library
# was, or it crashes.
if(DPC_X86_64_V3)
  if(DPC_X86_64_V4)
    set(dpc_march x86-64-v4)
  else()
    set(dpc_march x86-64-v3)
  endif()
  foreach(target IN LISTS dpc_core_targets)
    target_compile_options(${target} INTERFACE $<INSTALL_INTERFACE:-march=${dpc_march}>)
  endforeach()
endif()
install(TARGETS ${dpc_core_targets} dpc_core EXPORT jacobian_dpc_targets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
set(dpc_package_dir ${CMAKE_INSTALL_LIBDIR}/cmake/jacobian_dpc)
install(EXPORT jacobian_dpc_targets NAMESPACE jacobian_dpc:: FILE jacobian_dpcTargets.cmake
  DESTINATION ${dpc_package_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/jacobian_dpcConfig.cmake.in
  ${PROJECT_BINARY_DIR}/jacobian_dpcConfig.cmake INSTALL_DESTINATION ${dpc_package_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/jacobian_dpcConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/jacobian_dpcConfig.cmake ${PROJECT_BINARY_DIR}/jacobian_dpcConfigVersion.cmake
  DESTINATION ${dpc_package_dir})

# The programs and what they read at run time (BusParticipant finds
# <bin>/../share/dpc/fastdds/loopback.xml, dpc dashboard <bin>/../share/dpc/dashboard).
install(TARGETS dpc dpc-driver dpc-controller dpc-polarimeter dpc-emulator RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES ${PROJECT_SOURCE_DIR}/deploy/fastdds/loopback.xml DESTINATION ${CMAKE_INSTALL_DATADIR}/dpc/fastdds)
install(PROGRAMS ${PROJECT_SOURCE_DIR}/deploy/fastdds/make_profile.sh DESTINATION ${CMAKE_INSTALL_DATADIR}/dpc/fastdds)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/deploy/scenarios/ DESTINATION ${CMAKE_INSTALL_DATADIR}/dpc/scenarios
  FILES_MATCHING PATTERN "*.pbtxt")
install(FILES ${PROJECT_SOURCE_DIR}/idl/dpc/bench.idl DESTINATION ${CMAKE_INSTALL_DATADIR}/dpc/idl/dpc)
install(PROGRAMS ${PROJECT_SOURCE_DIR}/deploy/security/make-bench-pki.sh DESTINATION ${CMAKE_INSTALL_DATADIR}/dpc/security)
install(FILES ${PROJECT_SOURCE_DIR}/tools/dpc/completion/dpc.bash
  DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions RENAME dpc)
