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
# disk list names the explore files (issue 34: they were "unknown data"): the map's grid and
# tiles, the graph's counts as disk map exported them, the saved state.
string(REGEX MATCH "map.yaml: ([0-9]+) tiles" tiles "${last_output}")
set(tiles ${CMAKE_MATCH_1})
run_ok("seqslam disk list" ${SEQSLAM_CLI} disk list ${WORK}/firmware.img)
if(NOT tiles OR
   NOT last_output MATCHES "\nmap [ 0-9]+  map tiles \\(1600x1600 cells of 50 mm\\): ${tiles} tiles; session [0-9]+, [0-9]+ tile records, ends cleanly\n"
   OR NOT last_output MATCHES "\ngraph [ 0-9]+  pose graph: ${node_rows} nodes, [0-9]+ edges \\([1-9][0-9]* loop closures\\), optimised to convergence, slot [12] of 2\n"
   OR NOT last_output MATCHES "\nstate [ 0-9]+  saved run state \\(explore, to continue\\): session [0-9]+, [1-9][0-9]* records, ends cleanly\n")
  message(FATAL_ERROR "disk list does not describe the map (${tiles} tiles), graph or state")
endif()
# Under a file size limit, SIGXFSZ at its default action (issue 34: it died with status 153
# and left its temporary): status 1 naming the file, no temporary left.
execute_process(COMMAND sh -c "ulimit -f 1 && exec \"$0\" disk map \"$1\" --out \"$2\""
                        ${SEQSLAM_CLI} ${WORK}/firmware.img ${WORK}/limited
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
file(GLOB temporaries ${WORK}/limited/.*.tmp-*)
if(NOT rc EQUAL 1 OR NOT err MATCHES "limited/map.pgm: write failed: File too large" OR temporaries)
  message(FATAL_ERROR "disk map under ulimit -f: status ${rc}, ${err} ${temporaries}")
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

# Continuing an explore run (docs/firmware.md, "Continuing an explore run"): the run stopped
# after 29 100 of the 30 653 snapshots (place 302 of 316, inside the revisit, so closures come
# both before and after the stop), its state saved on the card; then the whole recording as
# the replay and mode `continue`. The graph, the map and the results equal those of the one
# run above byte for byte.
run_ok("prefix" ${E2E_EXPLORE} prefix ${dream} ${WORK}/stopped.dream 29100)
run_ok("prepare the stopped run" ${E2E_EXPLORE} prepare ${WORK}/stopped.dream ${WORK}/continued.img)
run_ok("the stopped run" ${FIRMWARE} --disk ${WORK}/continued.img)
if(NOT last_output MATCHES "app: explore: run state saved \\([0-9]+ bytes\\)")
  message(FATAL_ERROR "the stopped run did not save its state")
endif()
file(COPY_FILE ${WORK}/continued.img ${WORK}/no_state.img)
run_ok("the whole recording as the replay" ${SEQSLAM_CLI} disk import ${WORK}/continued.img
       replay ${dream})
run_ok("mode continue" ${SEQSLAM_CLI} config write ${WORK}/continued.img --modes continue)
run_ok("the continued run" ${FIRMWARE} --disk ${WORK}/continued.img)
if(NOT last_output MATCHES "app: continuing the saved run after place 302 and snapshot 29100")
  message(FATAL_ERROR "the run did not continue from the saved state")
endif()
run_ok("disk map of the continued run" ${SEQSLAM_CLI} disk map ${WORK}/continued.img
       --out ${WORK}/continued)
run_ok("results of the one run" ${SEQSLAM_CLI} results ${WORK}/firmware.img --csv ${WORK}/one.csv)
run_ok("results of the continued run" ${SEQSLAM_CLI} results ${WORK}/continued.img
       --csv ${WORK}/continued/results.csv)
foreach(pair "map.pgm out/map.pgm" "graph_nodes.csv out/graph_nodes.csv"
             "graph_edges.csv out/graph_edges.csv" "results.csv one.csv")
  separate_arguments(pair)
  list(GET pair 0 continued_file)
  list(GET pair 1 one_file)
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${WORK}/continued/${continued_file}
                          ${WORK}/${one_file} RESULT_VARIABLE differ)
  if(NOT differ EQUAL 0)
    message(FATAL_ERROR "the continued run's ${continued_file} differs from the one run's")
  endif()
endforeach()

# Refusals, exit 2: a card without a library (freshly prepared), a state that is not one (the
# stopped run's card with junk in its state file), and a replay that does not begin with the
# saved run (the one run's card, whose state is at snapshot 30 653, with the stopped run's
# shorter recording as its replay).
# A refused start changes nothing: the card is byte for byte what it was (issue 34).
function(refused what image pattern)
  run_ok("${what}: mode continue" ${SEQSLAM_CLI} config write ${image} --modes continue)
  file(SHA256 ${image} before)
  execute_process(COMMAND ${FIRMWARE} --disk ${image}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 2 OR NOT "${out}${err}" MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: continuing should be refused (${rc}): ${out}${err}")
  endif()
  file(SHA256 ${image} after)
  if(NOT before STREQUAL after)
    message(FATAL_ERROR "${what}: the refused start changed the card")
  endif()
endfunction()
run_ok("a fresh card" ${E2E_EXPLORE} prepare ${WORK}/stopped.dream ${WORK}/fresh.img)
refused("no library" ${WORK}/fresh.img "app: library: DATA_LOSS")
file(COPY_FILE ${WORK}/no_state.img ${WORK}/junk_state.img)
run_ok("junk state" ${SEQSLAM_CLI} disk import ${WORK}/junk_state.img state ${WORK}/junk.bin)
refused("no saved state" ${WORK}/junk_state.img "reading the saved run: DATA_LOSS - .*magic")
file(COPY_FILE ${WORK}/firmware.img ${WORK}/wrong.img)
run_ok("a shorter replay" ${SEQSLAM_CLI} disk import ${WORK}/wrong.img replay
       ${WORK}/stopped.dream)
refused("another replay" ${WORK}/wrong.img
        "continuing: FAILED_PRECONDITION - the replay does not begin with the saved run")
