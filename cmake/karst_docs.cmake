# Build step (cmake -P): write the man page and the bash completion that the karst binary
# generates from its command table, each to a temporary name renamed into place.
#   -DKARST=path/to/karst -DMAN=karst.1 -DCOMPLETION=karst.bash
function(karst_doc out)
  execute_process(COMMAND ${KARST} ${ARGN} OUTPUT_FILE ${out}.tmp RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    file(REMOVE ${out}.tmp)
    message(FATAL_ERROR "karst ${ARGN} failed (${rc})")
  endif()
  file(RENAME ${out}.tmp ${out})
endfunction()
karst_doc(${MAN} help --man)
karst_doc(${COMPLETION} completion bash)
