# Helpers of the checks on lodestone-bench-rosensweig's CSV
# (check_rosensweig_onset.cmake, check_desk_toy.cmake); each sets `lines`
# (the CSV's rows after the header) and `lastFrame` before late_spacing.

# A decimal as a whole number of millionths (CMake has no floating-point math).
function(to_millionths value out)
  string(REGEX MATCH "^([0-9]+)(\\.([0-9]+))?" m "${value}")
  set(whole "${CMAKE_MATCH_1}")
  string(SUBSTRING "${CMAKE_MATCH_3}000000" 0 6 frac)
  string(REGEX REPLACE "^0+([0-9])" "\\1" frac "${frac}")
  math(EXPR v "${whole} * 1000000 + ${frac}")
  set(${out} ${v} PARENT_SCOPE)
endfunction()

# The fields of one CSV row `row`: ratio, frame, t (s), rms (cells), peaks;
# and lastFrame, the largest frame seen so far (a macro: they are the
# caller's).
macro(read_row row)
  string(REPLACE "," ";" _fields "${row}")
  list(GET _fields 1 ratio)
  list(GET _fields 3 frame)
  list(GET _fields 4 t)
  list(GET _fields 7 rms)
  list(GET _fields 8 peaks)
  if(frame GREATER lastFrame)
    set(lastFrame ${frame})
  endif()
endmacro()

# Mean nearest spike distance (millionths of the wavelength) over the last 10
# frames (`lastFrame` the last) of the rows in `lines` of ratio `which` (any
# ratio when empty).
function(late_spacing which out)
  math(EXPR from "${lastFrame} - 9")
  set(sum 0)
  set(count 0)
  foreach(line IN LISTS lines)
    string(REPLACE "," ";" f "${line}")
    list(GET f 1 ratio)
    list(GET f 3 frame)
    list(GET f 10 spacing)
    if((which STREQUAL "" OR ratio STREQUAL "${which}") AND frame GREATER_EQUAL from AND NOT spacing STREQUAL "nan")
      to_millionths(${spacing} v)
      math(EXPR sum "${sum} + ${v}")
      math(EXPR count "${count} + 1")
    endif()
  endforeach()
  if(count EQUAL 0)
    message(FATAL_ERROR "${which} H0_c: no spikes in the last 10 frames")
  endif()
  math(EXPR mean "${sum} / ${count}")
  set(${out} ${mean} PARENT_SCOPE)
endfunction()
