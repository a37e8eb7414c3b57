# The #include step of the embedded shaders (pdsm_glsl.cmake) on fixtures: nested and repeated
# includes, #line numbering, a chunk found in shaders/, a missing chunk. ctest glsl_include:
#   cmake -DWORK_DIR=DIR -P cmake/pdsm_glsl_test.cmake
include(${CMAKE_CURRENT_LIST_DIR}/pdsm_glsl.cmake)
if(NOT WORK_DIR)
  message(FATAL_ERROR "pass -DWORK_DIR=...")
endif()
file(MAKE_DIRECTORY ${WORK_DIR})

if(MISSING)  # the child run below
  file(WRITE ${WORK_DIR}/missing.frag "#version 330 core\n#include \"nowhere.glsl\"\n")
  pdsm_read_glsl(text ${WORK_DIR}/missing.frag)
  return()
endif()

function(expect_equal what got want)
  if(NOT got STREQUAL want)
    message(FATAL_ERROR "${what}:\n--- got\n${got}\n--- want\n${want}")
  endif()
endfunction()

# a includes b, which includes c; a includes c again (kept once). Semicolons survive.
file(WRITE ${WORK_DIR}/a.frag
  "#version 330 core\n// top\n#include \"b.glsl\"\n  #include \"c.glsl\"  // again\nvoid main() {}\n")
file(WRITE ${WORK_DIR}/b.glsl "float B() { return 1.0; }\n#include \"c.glsl\"\n")
file(WRITE ${WORK_DIR}/c.glsl "float C(float x) { return x; }")
pdsm_read_glsl(text ${WORK_DIR}/a.frag)
expect_equal("nested includes" "${text}" "#version 330 core
// top
// #include \"b.glsl\" (GLSL source string 1)
#line 1 1
float B() { return 1.0; }
// #include \"c.glsl\" (GLSL source string 2)
#line 1 2
float C(float x) { return x; }
#line 3 1
#line 4 0
// #include \"c.glsl\": already included
void main() {}
")

# From any folder, a name is also looked up in shaders/: the bias chunk both shadow-map
# shaders include.
file(WRITE ${WORK_DIR}/d.frag "#version 330 core\n#include \"common/shadow_bias.glsl\"\n")
pdsm_read_glsl(text ${WORK_DIR}/d.frag)
string(FIND "${text}" "float BiasedDepth(" at)
if(at EQUAL -1 OR text MATCHES "\n#include")
  message(FATAL_ERROR "common/shadow_bias.glsl not included from shaders/:\n${text}")
endif()

# A missing chunk stops the configure step, naming the includer.
execute_process(COMMAND ${CMAKE_COMMAND} -DWORK_DIR=${WORK_DIR} -DMISSING=1
                        -P ${CMAKE_CURRENT_LIST_FILE}
                RESULT_VARIABLE result ERROR_VARIABLE error)
# CMake wraps the message at a width that depends on the path's length: compare it unwrapped.
string(REGEX REPLACE "[ \n]+" " " error_line "${error}")
if(result EQUAL 0 OR NOT error_line MATCHES "missing.frag: #include \"nowhere.glsl\" not found")
  message(FATAL_ERROR "a missing chunk was not reported (exit ${result}):\n${error}")
endif()
message(STATUS "pdsm_read_glsl: ok")
