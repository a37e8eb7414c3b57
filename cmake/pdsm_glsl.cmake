# pdsm_read_glsl(<out_var> <file>): the text of a GLSL source with its `#include "name"` lines
# resolved, for embedding in a binary (as filament's shader chunks, e.g. common_shadowing.glsl,
# are included by the shaders that share them). GLSL has no #include of its own.
#
# - `name` is looked up beside the including file, then in shaders/ (so `common/x.glsl` works
#   from every folder). A name that is not found is a configure error naming the includer.
# - Each file is included once per shader; a second #include of it becomes a comment, so two
#   chunks may both include a third, and a cycle cannot recurse.
# - Every included file gets its own GLSL source-string number, announced in a comment, and
#   `#line` directives keep the driver's error positions right: "1:3(7)" is line 3 of the first
#   included file, "0:40(2)" line 40 of the shader itself.
# - Every file read becomes a CMAKE_CONFIGURE_DEPENDS of the calling folder: editing a chunk
#   re-runs the embedding, as editing the shader does.
set(PDSM_GLSL_INCLUDE_DIR ${CMAKE_CURRENT_LIST_DIR}/../shaders)
get_filename_component(PDSM_GLSL_INCLUDE_DIR ${PDSM_GLSL_INCLUDE_DIR} ABSOLUTE)

function(pdsm_read_glsl out_var file)
  get_filename_component(file ${file} ABSOLUTE)
  set_property(GLOBAL PROPERTY PDSM_GLSL_SEEN "${file}")
  _pdsm_glsl_expand(text "${file}" 0)
  get_property(seen GLOBAL PROPERTY PDSM_GLSL_SEEN)
  if(NOT CMAKE_SCRIPT_MODE_FILE)
    set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${seen})
  endif()
  set(${out_var} "${text}" PARENT_SCOPE)
endfunction()

# Appends `file`'s text to nothing and returns it in out_var, includes expanded; `number` is
# the GLSL source-string number of `file`.
function(_pdsm_glsl_expand out_var file number)
  file(READ "${file}" rest)
  get_filename_component(dir "${file}" DIRECTORY)
  set(include_line "(^|\n)[ \t]*#[ \t]*include[ \t]+\"([^\"\n]+)\"[^\n]*")
  set(done "")
  set(line_number 1)  # of the first line of `rest` in `file`
  while(rest MATCHES "${include_line}")
    set(match "${CMAKE_MATCH_0}")
    set(newline "${CMAKE_MATCH_1}")
    set(name "${CMAKE_MATCH_2}")
    string(FIND "${rest}" "${match}" at)
    string(LENGTH "${match}" match_length)
    string(SUBSTRING "${rest}" 0 ${at} head)
    math(EXPR tail_begin "${at} + ${match_length}")
    string(SUBSTRING "${rest}" ${tail_begin} -1 rest)
    string(APPEND done "${head}${newline}")
    # Lines before the #include, and the #include itself.
    string(REGEX MATCHALL "\n" head_newlines "${head}${newline}")
    list(LENGTH head_newlines count)
    math(EXPR line_number "${line_number} + ${count}")

    _pdsm_glsl_resolve(path "${name}" "${dir}" "${file}")
    get_property(seen GLOBAL PROPERTY PDSM_GLSL_SEEN)
    list(FIND seen "${path}" seen_at)
    if(NOT seen_at EQUAL -1)
      string(APPEND done "// #include \"${name}\": already included")
    else()
      set_property(GLOBAL APPEND PROPERTY PDSM_GLSL_SEEN "${path}")
      get_property(seen GLOBAL PROPERTY PDSM_GLSL_SEEN)
      list(LENGTH seen chunk_number)
      math(EXPR chunk_number "${chunk_number} - 1")
      _pdsm_glsl_expand(chunk "${path}" ${chunk_number})
      if(NOT chunk MATCHES "\n$")
        string(APPEND chunk "\n")
      endif()
      # The line after the #include is line_number + 1 of `file`.
      math(EXPR next_line "${line_number} + 1")
      string(APPEND done "// #include \"${name}\" (GLSL source string ${chunk_number})\n"
                         "#line 1 ${chunk_number}\n${chunk}#line ${next_line} ${number}")
    endif()
  endwhile()
  set(${out_var} "${done}${rest}" PARENT_SCOPE)
endfunction()

function(_pdsm_glsl_resolve out_var name dir includer)
  foreach(candidate "${dir}/${name}" "${PDSM_GLSL_INCLUDE_DIR}/${name}")
    if(EXISTS "${candidate}" AND NOT IS_DIRECTORY "${candidate}")
      get_filename_component(candidate "${candidate}" ABSOLUTE)
      set(${out_var} "${candidate}" PARENT_SCOPE)
      return()
    endif()
  endforeach()
  message(FATAL_ERROR "${includer}: #include \"${name}\" not found (looked in ${dir} and "
                      "${PDSM_GLSL_INCLUDE_DIR})")
endfunction()
