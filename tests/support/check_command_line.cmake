# Runs PROGRAM with ARGS (separated by '|') and fails unless it exits with
# EXIT_CODE and, where given, its stdout matches STDOUT and its stderr matches
# STDERR (regular expressions) and its stdout does not match NOT_STDOUT.
# Used for the command-line tests: exit code and message together, which a
# PASS_REGULAR_EXPRESSION alone (it ignores the exit code) cannot check.
string(REPLACE "|" ";" args "${ARGS}")
execute_process(COMMAND ${PROGRAM} ${args} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
set(problems "")
if(NOT rc STREQUAL "${EXIT_CODE}")
  string(APPEND problems "exit code ${rc}, expected ${EXIT_CODE}\n")
endif()
if(DEFINED STDOUT AND NOT out MATCHES "${STDOUT}")
  string(APPEND problems "stdout does not match '${STDOUT}'\n")
endif()
if(DEFINED NOT_STDOUT AND out MATCHES "${NOT_STDOUT}")
  string(APPEND problems "stdout matches '${NOT_STDOUT}'\n")
endif()
if(DEFINED STDERR AND NOT err MATCHES "${STDERR}")
  string(APPEND problems "stderr does not match '${STDERR}'\n")
endif()
if(problems)
  string(REPLACE ";" " " shown "${args}")
  message(FATAL_ERROR "${PROGRAM} ${shown}:\n${problems}--- stdout:\n${out}--- stderr:\n${err}")
endif()
