# Installs the build into a prefix, configures and builds a consumer project
# against it with find_package(Lodestone) (a C host of the plugin, C++ hosts
# of Lodestone::core and, when built, Lodestone::vdb_io), and runs them.
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix}
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "install failed")
endif()
set(expected include/lodestone/plugin/lodestone.h include/lodestone/core/stage/density_raster.h
             include/lodestone/core/stage/magnetic_stage.h lib/cmake/Lodestone/LodestoneConfig.cmake
             lib/cmake/Lodestone/LodestoneCoreTargets.cmake)
if(EXPECT_VDB_IO)
  list(APPEND expected include/lodestone/vdb_io/field_file.h lib/cmake/Lodestone/LodestoneVdbTargets.cmake)
endif()
foreach(f IN LISTS expected)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
                        -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_C_COMPILER=${C_COMPILER}
                        -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=Release
                        -DEXPECT_VDB_IO=${EXPECT_VDB_IO}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the consumer failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/build RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the consumer failed")
endif()
execute_process(COMMAND ${WORK_DIR}/build/consumer RESULT_VARIABLE rc OUTPUT_VARIABLE out)
message(STATUS "${out}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "API 1\\.")
  message(FATAL_ERROR "the consumer did not run: ${rc} ${out}")
endif()
execute_process(COMMAND ${WORK_DIR}/build/core_consumer RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "core consumer: converged 1")
  message(FATAL_ERROR "the core consumer failed: ${rc} ${out} ${err}")
endif()
if(EXPECT_VDB_IO)
  execute_process(COMMAND ${WORK_DIR}/build/vdb_consumer ${WORK_DIR}/fields.vdb
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}")
  if(NOT rc EQUAL 0 OR NOT out MATCHES "vdb consumer: density read back")
    message(FATAL_ERROR "the vdb_io consumer failed: ${rc} ${out} ${err}")
  endif()
endif()
