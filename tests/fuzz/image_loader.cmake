# fuzz_image_loader: the host image loader (tools/common: decode_gray, PNG through libpng with
# its checksums verified, JPEG checked by libjpeg, JPEG/BMP through stb_image, PGM/PPM) with
# property oracles (see fuzz_image_loader.cpp). tools/ is not part of the fuzz build, so the
# loader's sources are compiled here, with the fuzzer's instrumentation; a static library, so
# only the objects decode_gray and save_png need are linked. Included from
# tests/fuzz/CMakeLists.txt.
include(SeqslamImageLibs)
set(_seqslam_tools ${PROJECT_SOURCE_DIR}/tools/common)
add_library(fuzz_image_io STATIC
  ${_seqslam_tools}/src/image_io.cpp
  ${_seqslam_tools}/src/jpeg_check.cpp
  ${_seqslam_tools}/src/png_decode.cpp
  ${_seqslam_tools}/src/formats.cpp
  ${_seqslam_tools}/src/pnm.cpp
  # file_util.cpp (load_gray, save_png) and what it needs
  ${_seqslam_tools}/src/file_util.cpp
  ${_seqslam_tools}/src/input_file.cpp
  ${_seqslam_tools}/src/output_file.cpp
  ${_seqslam_tools}/src/dataset.cpp
  ${_seqslam_tools}/src/reduce.cpp)
target_include_directories(fuzz_image_io
  PUBLIC ${_seqslam_tools}/include ${PROJECT_SOURCE_DIR}/tests/support
  PRIVATE ${_seqslam_tools}/src)
target_link_libraries(fuzz_image_io
  PUBLIC seqslam seqslam_stb PNG::PNG ZLIB::ZLIB JPEG::JPEG
  # output_file.cpp: file locks and the file size limit (seqslam/hal/host_file.h)
  PRIVATE seqslam_hal_host seqslam_warnings)

add_executable(make_image_seeds make_image_seeds.cpp)
target_link_libraries(make_image_seeds PRIVATE fuzz_image_io seqslam_warnings)
add_test(NAME fuzz_image_seeds COMMAND make_image_seeds image_corpus)
set_tests_properties(fuzz_image_seeds PROPERTIES FIXTURES_SETUP fuzz_image_corpus
                     WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})

add_executable(fuzz_image_loader fuzz_image_loader.cpp)
target_link_libraries(fuzz_image_loader PRIVATE fuzz_image_io seqslam_warnings)
target_link_options(fuzz_image_loader PRIVATE -fsanitize=fuzzer)
# Deterministic as the others: a fixed seed and number of runs (SEQSLAM_FUZZ_RUNS, set by
# CMakeLists.txt) from the seed corpus.
add_test(NAME fuzz_image_loader
         COMMAND fuzz_image_loader -seed=1 -runs=${SEQSLAM_FUZZ_RUNS} -max_len=8192 image_corpus)
set_tests_properties(fuzz_image_loader PROPERTIES FIXTURES_REQUIRED fuzz_image_corpus
                     WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR} LABELS fuzz)
