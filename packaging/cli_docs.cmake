# cmake -DTETPACK=<tetpack> -DCOMMANDS_OUT=<file> -DCOMPLETION_OUT=<file> -P cli_docs.cmake
# What the man page and the bash completion know of the command line, read from the command itself:
# `tetpack --help` lists the subcommands ("  name  summary" lines), each `tetpack NAME --help` its options
# ("  --flag METAVAR  help" or "  -o, --flag ..." lines; a metavar like tet16|tet20|tet32 is the list of
# values). So a new subcommand or option, or a changed option table (tools/scene/option_table.c), shows
# up in both without an edit here.
#   COMMANDS_OUT: a help2man include file (-i) with a COMMANDS section: each subcommand's --help as is.
#   COMPLETION_OUT: the bash completion script for tetpack.

function(run_help out)
  execute_process(COMMAND ${TETPACK} ${ARGN} --help OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${TETPACK} ${ARGN} --help failed (exit ${rc})")
  endif()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# roff for preformatted help text: backslashes escaped, minus signs as \-, no line read as a request.
function(to_roff out text)
  string(REPLACE "\\" "\\e" text "${text}")
  string(REPLACE "-" "\\-" text "${text}")
  string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

run_help(top_help)
string(REGEX MATCHALL "\n  [a-z][a-z0-9-]* " command_lines "${top_help}")
set(commands)
foreach(line ${command_lines})
  string(STRIP "${line}" name)
  list(APPEND commands ${name})
endforeach()
if(NOT commands)
  message(FATAL_ERROR "`${TETPACK} --help` lists no subcommands")
endif()

set(man "[COMMANDS]\n")
set(option_cases "")
set(value_cases "")
foreach(cmd ${commands})
  run_help(help ${cmd})
  to_roff(help_roff "${help}")
  string(APPEND man ".SS \"tetpack ${cmd}\"\n.nf\n${help_roff}.fi\n")

  # Option lines: two spaces, an optional short alias, the flag, an optional metavar.
  string(REGEX MATCHALL "\n  (-[A-Za-z0-9], )?--[a-z0-9-]+(\\[=[A-Z]+\\])?( [^ \n]+)?" option_lines "${help}")
  set(flags)
  foreach(line ${option_lines})
    string(REGEX MATCH "--[a-z0-9-]+" flag "${line}")
    string(REGEX MATCH "^\n  -[A-Za-z0-9]," alias "${line}")
    if(alias)
      string(REGEX MATCH "-[A-Za-z0-9]" alias "${alias}")
      list(APPEND flags ${alias})
    endif()
    if(line MATCHES "\\[=[A-Z]+\\]")
      list(APPEND flags "${flag}" "${flag}=")
    else()
      list(APPEND flags "${flag}")
    endif()
    # A metavar of lowercase words joined by | is the option's list of values.
    if(line MATCHES " ([a-z0-9_]+(\\|[a-z0-9_]+)+)$")
      string(REPLACE "|" " " values "${CMAKE_MATCH_1}")
      string(APPEND value_cases "        \"${cmd} ${flag}\") values=\"${values}\" ;;\n")
      if(alias)
        string(APPEND value_cases "        \"${cmd} ${alias}\") values=\"${values}\" ;;\n")
      endif()
    endif()
  endforeach()
  list(REMOVE_DUPLICATES flags)
  list(JOIN flags " " flags)
  string(APPEND option_cases "        ${cmd}) opts=\"${flags} --help\" ;;\n")
endforeach()
file(WRITE ${COMMANDS_OUT} "${man}")

list(JOIN commands " " command_words)
file(WRITE ${COMPLETION_OUT} "# bash completion for tetpack: subcommands, their options and the values of options that take
# one of a fixed list, generated from tetpack's own --help (packaging/cli_docs.cmake); files otherwise.
_tetpack()
{
    local cur=\${COMP_WORDS[COMP_CWORD]} prev=\${COMP_WORDS[COMP_CWORD-1]}
    if [ \"\$COMP_CWORD\" -eq 1 ]; then
        mapfile -t COMPREPLY < <(compgen -W \"${command_words} --help --version\" -- \"\$cur\")
        return
    fi
    local cmd=\${COMP_WORDS[1]} opts=\"\" values=\"\"
    case \$cmd in
${option_cases}        *) return ;;
    esac
    case \"\$cmd \$prev\" in
${value_cases}    esac
    if [ -n \"\$values\" ]; then
        mapfile -t COMPREPLY < <(compgen -W \"\$values\" -- \"\$cur\")
    elif [[ \$cur == -* ]]; then
        mapfile -t COMPREPLY < <(compgen -W \"\$opts\" -- \"\$cur\")
        [[ \${COMPREPLY[0]-} == *= ]] && compopt -o nospace
    else
        compopt -o filenames
        mapfile -t COMPREPLY < <(compgen -f -- \"\$cur\")
    fi
}
complete -F _tetpack tetpack
")
