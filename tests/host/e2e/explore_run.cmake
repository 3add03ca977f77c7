# The explore mode end to end on the PC (docs/firmware.md, "Explore"):
#   seqslam-sim explore-short (~65 m, the end revisits the start) -> e2e_explore prepare ->
#   two copies: e2e_explore run (the application in-process: closures true to the ground
#   truth, RMSE below dead reckoning, map and graph files reload to exactly the application's
#   grid and graph) | seqslam-firmware --disk -> the two images identical byte for byte ->
#   seqslam disk map exports the map (PGM + YAML) and the graph (CSV) -> seqslam slam on the
#   same recording gives the same graph and map byte for byte -> a graph file of the wrong
#   kind is refused with the reason.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
function(run_ok what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${what}:\n${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc})")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

run_ok("seqslam-sim" ${SIM} generate --scenario explore-short --seed 1 --out ${WORK}/sim)
set(dream ${WORK}/sim/explore_short_noon-lamps.dream)
run_ok("prepare" ${E2E_EXPLORE} prepare ${dream} ${WORK}/prepared.img)
file(COPY_FILE ${WORK}/prepared.img ${WORK}/app.img)
file(COPY_FILE ${WORK}/prepared.img ${WORK}/firmware.img)
run_ok("in-process run and checks" ${E2E_EXPLORE} run ${WORK}/app.img ${dream})
run_ok("seqslam-firmware" ${FIRMWARE} --disk ${WORK}/firmware.img)
if(NOT last_output MATCHES "closure node [0-9]+ with node [0-9]+"
   OR NOT last_output MATCHES "app: explore: map and graph saved"
   OR NOT last_output MATCHES "app: closures [1-9]")
  message(FATAL_ERROR "the firmware's output does not show closures and saved outputs")
endif()
file(SHA256 ${WORK}/app.img app_hash)
file(SHA256 ${WORK}/firmware.img firmware_hash)
if(NOT app_hash STREQUAL firmware_hash)
  message(FATAL_ERROR "seqslam-firmware and the in-process run wrote different images")
endif()

run_ok("seqslam disk map" ${SEQSLAM_CLI} disk map ${WORK}/firmware.img --out ${WORK}/out)
foreach(f map.pgm map.yaml graph_nodes.csv graph_edges.csv)
  if(NOT EXISTS ${WORK}/out/${f})
    message(FATAL_ERROR "disk map did not write ${f}")
  endif()
endforeach()
file(STRINGS ${WORK}/out/graph_nodes.csv node_lines)
list(LENGTH node_lines node_rows)
math(EXPR node_rows "${node_rows} - 1")
if(NOT last_output MATCHES "graph_nodes.csv, .*graph_edges.csv: ${node_rows} nodes, [0-9]+ edges \\([1-9][0-9]* loop closures\\), optimised to convergence")
  message(FATAL_ERROR "disk map's graph summary does not match its CSV (${node_rows} rows)")
endif()
file(STRINGS ${WORK}/out/map.yaml yaml)
if(NOT yaml MATCHES "resolution: 0.05")
  message(FATAL_ERROR "map.yaml: not 5 cm cells")
endif()

# One explorer (explorer.h): `seqslam slam` on the same recording builds the same graph and
# the same map as the firmware, byte for byte (the CSVs come from one writer, graph_csv.h;
# the map from one exporter, grid_export.h).
run_ok("seqslam slam" ${SEQSLAM_CLI} slam ${dream} --out ${WORK}/slam --quiet)
foreach(pair "graph_nodes.csv graph_nodes.csv" "graph_edges.csv graph_edges.csv"
             "explorer_map.pgm map.pgm")
  separate_arguments(pair)
  list(GET pair 0 slam_file)
  list(GET pair 1 card_file)
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${WORK}/slam/${slam_file}
                          ${WORK}/out/${card_file} RESULT_VARIABLE differ)
  if(NOT differ EQUAL 0)
    message(FATAL_ERROR "seqslam slam's ${slam_file} differs from the firmware's ${card_file}")
  endif()
endforeach()

# A graph file of another kind: refused with the reason, exit status 1.
file(COPY_FILE ${WORK}/firmware.img ${WORK}/bad.img)
file(WRITE ${WORK}/junk.bin "not a graph log")
run_ok("import junk" ${SEQSLAM_CLI} disk import ${WORK}/bad.img graph ${WORK}/junk.bin)
execute_process(COMMAND ${SEQSLAM_CLI} disk map ${WORK}/bad.img --out ${WORK}/bad
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT "${out}${err}" MATCHES "graph: not a usable graph: .*wrong magic")
  message(FATAL_ERROR "disk map should refuse a foreign graph file (${rc}): ${out}${err}")
endif()
