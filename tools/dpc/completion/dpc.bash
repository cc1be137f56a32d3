# bash completion for dpc (installed as share/bash-completion/completions/dpc; or `source` it).
# The commands and options come from the dpc being completed (its --help), so they are always
# the ones it has: `dpc si<TAB>` → sim, `dpc sim --me<TAB>` → --method, `dpc topic echo <TAB>` →
# the topics, `dpc sim <TAB>` → scenario files (*.pbtxt), `--plot <TAB>` → files.
_dpc() {
  local cur prev words cword
  if declare -F _init_completion >/dev/null; then
    _init_completion || return
  else
    cur=${COMP_WORDS[COMP_CWORD]}
    prev=${COMP_WORDS[COMP_CWORD - 1]}
    words=("${COMP_WORDS[@]}")
    cword=$COMP_CWORD
  fi
  local dpc=${words[0]}
  local commands
  commands=$("$dpc" --help 2>/dev/null | awk '/^Subcommands:/ { on = 1; next } on && /^  [a-z]/ { print $1 }' | tr '\n' ' ')
  # The command being completed: the first word after dpc that is one of its commands.
  local command="" i
  for ((i = 1; i < cword; i++)); do
    if [[ " $commands " == *" ${words[i]} "* ]]; then
      command=${words[i]}
      break
    fi
  done
  if [[ -z $command ]]; then
    mapfile -t COMPREPLY < <(compgen -W "$commands --help --version" -- "$cur")
    return
  fi
  case $prev in
    --plot | --trace | --csv | --json-out | -o | --output | --assets | --security-dir | --logs)
      mapfile -t COMPREPLY < <(compgen -f -- "$cur")
      return ;;
    --scenario)
      mapfile -t COMPREPLY < <(compgen -f -X '!*.pbtxt' -- "$cur"; compgen -d -- "$cur")
      return ;;
    --topics)
      mapfile -t COMPREPLY < <(compgen -W "sample command state status device target request reply summary" -- "$cur")
      return ;;
  esac
  if [[ $command == topic ]]; then
    local sub="" j
    for ((j = i + 1; j < cword; j++)); do
      case ${words[j]} in list | echo | hz) sub=${words[j]}; break ;; esac
    done
    if [[ -z $sub ]]; then
      mapfile -t COMPREPLY < <(compgen -W "list echo hz" -- "$cur")
      return
    fi
    if [[ $cur != -* && $prev == "$sub" ]]; then
      mapfile -t COMPREPLY < <(compgen -W "sample command state status device target request reply summary" -- "$cur")
      return
    fi
    command="topic $sub"
  fi
  if [[ $cur == -* ]]; then
    local options
    # shellcheck disable=SC2086
    options=$("$dpc" $command --help 2>/dev/null | grep -oE -- '(^|[ ,])--[a-z0-9][a-z0-9-]*' | tr -d ' ,' | sort -u)
    mapfile -t COMPREPLY < <(compgen -W "$options" -- "$cur")
    return
  fi
  case $command in
    sim | sweep) mapfile -t COMPREPLY < <(compgen -f -X '!*.pbtxt' -- "$cur"; compgen -d -- "$cur") ;;
    plot) mapfile -t COMPREPLY < <(compgen -f -- "$cur") ;;
    info | replay | evaluate) mapfile -t COMPREPLY < <(compgen -f -X '!*.mcap' -- "$cur"; compgen -d -- "$cur") ;;
    calibrate) mapfile -t COMPREPLY < <(compgen -f -X '!*.pbtxt' -- "$cur"; compgen -d -- "$cur") ;;
  esac
}
complete -F _dpc dpc
