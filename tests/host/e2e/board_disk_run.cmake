# The end-to-end run on the emulated board, compared with the host build bit for bit:
#   e2e_disk prepare -> two identical copies of the disk image ->
#   QEMU: seqslam_fw_app.elf on copy 1 | host: seqslam-firmware on copy 2 ->
#   the two images must be identical byte for byte -> e2e_disk check (results equal to the
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
file(COPY_FILE ${WORK}/prepared.img ${WORK}/board.img)
file(COPY_FILE ${WORK}/prepared.img ${WORK}/host.img)

execute_process(COMMAND ${QEMU_RUN} --disk ${WORK}/board.img ${BOARD_FIRMWARE}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "board:\n${out}${err}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "board: run complete")
  message(FATAL_ERROR "the board run failed (${rc})")
endif()
execute_process(COMMAND ${HOST_FIRMWARE} --disk ${WORK}/host.img RESULT_VARIABLE rc
                OUTPUT_VARIABLE hout)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the host run failed (${rc}):\n${hout}")
endif()

file(SHA256 ${WORK}/board.img board_hash)
file(SHA256 ${WORK}/host.img host_hash)
file(SHA256 ${WORK}/prepared.img prepared_hash)
if(board_hash STREQUAL prepared_hash)
  message(FATAL_ERROR "the board wrote nothing to its disk image")
endif()
if(NOT board_hash STREQUAL host_hash)
  message(FATAL_ERROR "board and host disk images differ (board ${board_hash}, host ${host_hash})")
endif()
message(STATUS "board and host disk images are identical (sha256 ${board_hash})")
execute_process(COMMAND ${E2E_DISK} check ${WORK}/board.img RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "check of the board's results failed")
endif()
