# Runs umbra_explore_study for 3 s of simulated time with small images and
# checks that it succeeds and writes every file it promises (coverage.png
# only when python3 has matplotlib, umbra.html only in builds with the viewer).
file(REMOVE_RECURSE "${OUT}")
execute_process(COMMAND "${STUDY}" --out "${OUT}" --budget 3 --image-width 48 --image-height 26 --coverage-period 0.5
                RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE output)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "umbra_explore_study failed (${result}):\n${output}")
endif()
foreach(file coverage.csv summary.md summary.json umbra.umb)
  if(NOT EXISTS "${OUT}/${file}")
    message(FATAL_ERROR "umbra_explore_study wrote no ${file}:\n${output}")
  endif()
endforeach()
file(STRINGS "${OUT}/coverage.csv" rows)
list(LENGTH rows row_count)
list(GET rows 0 header)
if(NOT header STREQUAL "time_s,umbra_explored_m3,umbra_coverage_percent,umbra_memory_mib,octomap_explored_m3,octomap_coverage_percent,octomap_memory_mib"
   OR NOT row_count EQUAL 8)
  message(FATAL_ERROR "coverage.csv: unexpected header or ${row_count} rows (want a header and 7 rows of 0.5 s):\n${header}")
endif()
if(NOT output MATCHES "coverage.png not written" AND NOT EXISTS "${OUT}/coverage.png")
  message(FATAL_ERROR "no coverage.png and no word why:\n${output}")
endif()
if(NOT output MATCHES "umbra.html not written" AND NOT EXISTS "${OUT}/umbra.html")
  message(FATAL_ERROR "no umbra.html and no word why:\n${output}")
endif()
