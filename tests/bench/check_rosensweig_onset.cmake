# The Rosensweig onset and spacing of examples/scenes/rosensweig.json
# (docs/ferrofluid.md): runs lodestone-bench-rosensweig at 0.8, 1.15 and 1.3
# times the onset field H0_c and checks its CSV:
#   - 0.8 H0_c stays flat: the surface's rms height stays below half a cell
#     from 0.2 s on (measured: at most 0.24 cells);
#   - 1.15 H0_c: the spikes' mean nearest distance over the last 10 frames
#     within 15% of lambda_c (measured 1.01 lambda_c);
#   - 1.3 H0_c forms spikes: rms height above one cell at the end (measured
#     1.72), at least 6 spikes (9), closer together than at 1.15 H0_c
#     (0.88 lambda_c: above the onset the fastest-growing wavelength
#     shortens).
#
#   cmake -DBENCH=path/to/lodestone-bench-rosensweig -DOUT=dir -P check_rosensweig_onset.cmake
foreach(var BENCH OUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "check_rosensweig_onset: ${var} is not set")
  endif()
endforeach()
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${BENCH} --ratios 0.8,1.15,1.3 --csv ${OUT}/rosensweig.csv --table ${OUT}/rosensweig.md
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "lodestone-bench-rosensweig exited with ${rc}:\n${out}\n${err}")
endif()
include(${CMAKE_CURRENT_LIST_DIR}/rosensweig_csv.cmake)
file(STRINGS ${OUT}/rosensweig.csv lines)
list(POP_FRONT lines header)
if(NOT header MATCHES "^law,ratio,applied_H_A_per_m,frame,time_s,range_m,range_cells,rms_cells,peaks,mean_nearest_m,mean_nearest_over_lambda,tallest_cells,")
  message(FATAL_ERROR "unexpected CSV header: ${header}")
endif()

set(flatWorst 0)
set(lastFrame 0)
foreach(line IN LISTS lines)
  read_row("${line}")
  if(ratio STREQUAL "0.8" AND t GREATER_EQUAL 0.2 AND rms GREATER flatWorst)
    set(flatWorst ${rms})
  endif()
  if(ratio STREQUAL "1.3")
    set(endRms ${rms})
    set(endPeaks ${peaks})
  endif()
endforeach()

late_spacing(1.15 spacingLow)
late_spacing(1.3 spacingHigh)

message(STATUS "0.8 H0_c: largest rms height from 0.2 s on ${flatWorst} cells; 1.15 H0_c: mean nearest spike distance "
               "${spacingLow}e-6 lambda_c; 1.3 H0_c: rms ${endRms} cells, ${endPeaks} spikes, mean nearest distance "
               "${spacingHigh}e-6 lambda_c (last 10 frames)")
if(NOT flatWorst LESS 0.5)
  message(FATAL_ERROR "0.8 H0_c: the surface did not stay flat (rms ${flatWorst} cells >= 0.5)")
endif()
if(spacingLow LESS 850000 OR spacingLow GREATER 1150000)
  message(FATAL_ERROR "1.15 H0_c: mean spike distance ${spacingLow}e-6 lambda_c, not within 15% of lambda_c")
endif()
if(NOT endRms GREATER 1.0 OR endPeaks LESS 6)
  message(FATAL_ERROR "1.3 H0_c: no spikes (rms ${endRms} cells, ${endPeaks} spikes)")
endif()
if(NOT spacingHigh LESS spacingLow)
  message(FATAL_ERROR "1.3 H0_c: spikes not closer (${spacingHigh}e-6 lambda_c) than at 1.15 H0_c (${spacingLow}e-6)")
endif()
