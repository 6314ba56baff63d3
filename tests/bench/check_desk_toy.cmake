# The desk toy (examples/scenes/desk_toy.json, docs/ferrofluid.md): runs
# lodestone-bench-rosensweig --sources scene on the scene and on a copy with
# a 0.7 T magnet instead of 1.45 T, and checks their CSVs against the onset
# taken with the magnet's pull (field/rosensweig_onset.h, gravityNearMagnet):
#   - 0.7 T: the centre stays below the onset field (measured 0.78 H0_c)
#     and the surface flat: rms height below half a cell from 0.2 s on
#     (measured at most 0.37 cells);
#   - 1.45 T: the centre above 1.2 H0_c (measured 1.38), and spikes: rms
#     height above a cell at the end (measured 1.57), at least 10 spikes
#     (41), their mean nearest distance over the last 10 frames between 0.5
#     and 1.0 times the wavelength at the centre (0.64; the wavelength with
#     gravity alone would be 1.5 times the one with the pull).
#
#   cmake -DBENCH=path/to/lodestone-bench-rosensweig -DSCENE=desk_toy.json -DOUT=dir -P check_desk_toy.cmake
foreach(var BENCH SCENE OUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "check_desk_toy: ${var} is not set")
  endif()
endforeach()
file(MAKE_DIRECTORY ${OUT})
file(READ ${SCENE} scene)
string(REPLACE "\"remanence\": 1.45" "\"remanence\": 0.7" weak "${scene}")
if(weak STREQUAL scene)
  message(FATAL_ERROR "${SCENE}: no \"remanence\": 1.45 to weaken")
endif()
file(WRITE ${OUT}/desk_toy_weak.json "${weak}")
include(${CMAKE_CURRENT_LIST_DIR}/rosensweig_csv.cmake)

foreach(run strong weak)
  if(run STREQUAL "strong")
    set(file ${SCENE})
  else()
    set(file ${OUT}/desk_toy_weak.json)
  endif()
  execute_process(COMMAND ${BENCH} --scene ${file} --sources scene --radius 0.024 --csv ${OUT}/${run}.csv
                          --table ${OUT}/${run}.md
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "lodestone-bench-rosensweig (${run}) exited with ${rc}:\n${out}\n${err}")
  endif()
  file(STRINGS ${OUT}/${run}.csv lines)
  list(POP_FRONT lines header)
  if(NOT header MATCHES ",mean_nearest_over_lambda,tallest_cells,centre_applied_H_A_per_m,")
    message(FATAL_ERROR "unexpected CSV header: ${header}")
  endif()
  set(lastFrame 0)
  set(worstRms 0)
  foreach(line IN LISTS lines)
    read_row("${line}")
    if(t GREATER_EQUAL 0.2 AND rms GREATER worstRms)
      set(worstRms ${rms})
    endif()
    set(endRatio ${ratio})
    set(endRms ${rms})
    set(endPeaks ${peaks})
  endforeach()
  if(run STREQUAL "strong")
    late_spacing("" spacing)
    message(STATUS "1.45 T: ${endRatio} H0_c at the centre, rms ${endRms} cells, ${endPeaks} spikes, mean nearest "
                   "distance ${spacing}e-6 lambda (last 10 frames)")
    if(NOT endRatio GREATER 1.2)
      message(FATAL_ERROR "1.45 T: the centre is at ${endRatio} H0_c, not above 1.2")
    endif()
    if(NOT endRms GREATER 1.0 OR endPeaks LESS 10)
      message(FATAL_ERROR "1.45 T: no spikes (rms ${endRms} cells, ${endPeaks} spikes)")
    endif()
    if(spacing LESS 500000 OR spacing GREATER 1000000)
      message(FATAL_ERROR "1.45 T: mean spike distance ${spacing}e-6 lambda, not within 0.5-1.0 lambda")
    endif()
  else()
    message(STATUS "0.7 T: ${endRatio} H0_c at the centre, largest rms height from 0.2 s on ${worstRms} cells")
    if(NOT endRatio LESS 1.0)
      message(FATAL_ERROR "0.7 T: the centre is at ${endRatio} H0_c, not below the onset")
    endif()
    if(NOT worstRms LESS 0.5)
      message(FATAL_ERROR "0.7 T: the surface did not stay flat (rms ${worstRms} cells >= 0.5)")
    endif()
  endif()
endforeach()
