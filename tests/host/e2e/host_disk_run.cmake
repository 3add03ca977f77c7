# prepare -> seqslam-firmware --disk -> check, on the host.
# Optional: SEQSLAM_CLI and CONFIG_ARGS (one string, split like a shell command line) rewrite
# the prepared run configuration with `seqslam config write IMAGE CONFIG_ARGS` before the run
# (the way a user prepares a card); EXPECT is a regular expression the firmware's output must
# match.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
execute_process(COMMAND ${E2E_DISK} prepare ${WORK}/disk.img RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "prepare failed")
endif()
if(DEFINED CONFIG_ARGS)
  separate_arguments(config_args UNIX_COMMAND "${CONFIG_ARGS}")
  execute_process(COMMAND ${SEQSLAM_CLI} config write ${WORK}/disk.img ${config_args}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "seqslam config write failed (${rc})")
  endif()
endif()
execute_process(COMMAND ${FIRMWARE} --disk ${WORK}/disk.img RESULT_VARIABLE rc OUTPUT_VARIABLE out)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "seqslam-firmware failed (${rc})")
endif()
if(DEFINED EXPECT AND NOT out MATCHES "${EXPECT}")
  message(FATAL_ERROR "the firmware's output does not match /${EXPECT}/")
endif()
execute_process(COMMAND ${E2E_DISK} check ${WORK}/disk.img RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "check failed")
endif()
