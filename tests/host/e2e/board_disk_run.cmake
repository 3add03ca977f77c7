# The end-to-end run on the emulated board, compared with the host build bit for bit:
#   e2e_disk prepare -> two identical copies of the disk image ->
#   QEMU: seqslam_fw_app.elf on copy 1 | host: seqslam-firmware on copy 2 ->
#   the two images must be identical byte for byte, and the card requests counted (the `card:`
#   lines) equal -> e2e_disk check (results equal to the
#   core on the same images, recording equal to the replay).
foreach(tool E2E_DISK HOST_FIRMWARE)
  if(NOT EXISTS ${${tool}})
    message(FATAL_ERROR "${${tool}} is missing: build the host preset first (make test-host)")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
execute_process(COMMAND ${E2E_DISK} prepare ${WORK}/prepared.img RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "prepare failed")
endif()
# board_and_host(<name>): the board and the host run copies of ${WORK}/<name>.img; the two
# images must come out identical and different from the input, and e2e_disk check must pass.
function(board_and_host name)
  file(COPY_FILE ${WORK}/${name}.img ${WORK}/${name}.board.img)
  file(COPY_FILE ${WORK}/${name}.img ${WORK}/${name}.host.img)
  execute_process(COMMAND ${QEMU_RUN} --disk ${WORK}/${name}.board.img ${BOARD_FIRMWARE}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "board (${name}):\n${out}${err}")
  if(NOT rc EQUAL 0 OR NOT out MATCHES "board: run complete")
    message(FATAL_ERROR "the board run failed (${name}, ${rc})")
  endif()
  execute_process(COMMAND ${HOST_FIRMWARE} --disk ${WORK}/${name}.host.img RESULT_VARIABLE rc
                  OUTPUT_VARIABLE hout)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the host run failed (${name}, ${rc}):\n${hout}")
  endif()
  file(SHA256 ${WORK}/${name}.board.img board_hash)
  file(SHA256 ${WORK}/${name}.host.img host_hash)
  file(SHA256 ${WORK}/${name}.img prepared_hash)
  if(board_hash STREQUAL prepared_hash)
    message(FATAL_ERROR "the board wrote nothing to its disk image (${name})")
  endif()
  if(NOT board_hash STREQUAL host_hash)
    message(FATAL_ERROR
            "board and host disk images differ (${name}: board ${board_hash}, host ${host_hash})")
  endif()
  message(STATUS "board and host disk images are identical (${name}, sha256 ${board_hash})")
  # The PC build is the board's simulator: the same card requests too (the card time it
  # models is the board's).
  string(REGEX MATCH "card:[ 0-9]+" board_card "${out}")
  string(REGEX MATCH "card:[ 0-9]+" host_card "${hout}")
  if(board_card STREQUAL "" OR NOT board_card STREQUAL host_card)
    message(FATAL_ERROR "board and host card requests differ (${name}): '${board_card}' vs '${host_card}'")
  endif()
  execute_process(COMMAND ${E2E_DISK} check ${WORK}/${name}.board.img RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "check of the board's results failed (${name})")
  endif()
endfunction()

# The route search (the default configuration of e2e_disk prepare).
board_and_host(prepared)

# The heuristic matcher, the run configuration's other choice, on the same card.
get_filename_component(host_bin ${HOST_FIRMWARE} DIRECTORY)
set(seqslam_cli ${host_bin}/seqslam)
if(EXISTS ${seqslam_cli})
  file(COPY_FILE ${WORK}/prepared.img ${WORK}/heuristic.img)
  execute_process(COMMAND ${seqslam_cli} config write ${WORK}/heuristic.img --modes repeat,record
                          --matcher heuristic
                  RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "seqslam config write --matcher heuristic failed (${rc})")
  endif()
  board_and_host(heuristic)
  # The explore mode (SEQSLAM_APP_MAPPING=OFF on the board: it does not fit).
  file(COPY_FILE ${WORK}/prepared.img ${WORK}/explore.img)
  execute_process(COMMAND ${seqslam_cli} config write ${WORK}/explore.img --modes explore
                  RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "seqslam config write --modes explore failed (${rc})")
  endif()
  file(SHA256 ${WORK}/explore.img configured_hash)
  execute_process(COMMAND ${QEMU_RUN} --disk ${WORK}/explore.img ${BOARD_FIRMWARE}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "board, explore configured:\n${out}${err}")
  # storage::check_run_config's RunIssue::kMappingNotBuilt: the board prints its code (RC2,
  # `seqslam explain RC2`: "explore: mapping not built in").
  if(NOT rc EQUAL 2 OR NOT out MATCHES "app: configuration: FAILED_PRECONDITION - RC2")
    message(FATAL_ERROR "the board should refuse the explore mode at start (status ${rc})")
  endif()
  file(SHA256 ${WORK}/explore.img after_hash)
  if(NOT after_hash STREQUAL configured_hash)
    message(FATAL_ERROR "the board changed a disk image it refused to run")
  endif()
else()
  message(STATUS "${seqslam_cli} missing: the heuristic run and the explore refusal are not checked")
endif()
