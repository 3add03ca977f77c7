# The image libraries of the host image I/O (tools/common, and the image fuzz target in
# tests/fuzz): GLOBAL imported targets, so the tests that build images link them too.
#   seqslam_stb  stb from the system (Debian: libstb-dev): stb_image for JPEG and BMP,
#                stb_image_write for writing; headers as SYSTEM includes (their warnings do not
#                count), the implementations from libstb.
#   PNG::PNG     libpng (Debian: libpng-dev), which reads PNGs with their CRCs and Adler-32
#                checked; ZLIB::ZLIB comes with it.
#   JPEG::JPEG   libjpeg (Debian: libjpeg-dev, libjpeg-turbo), which checks a JPEG for corrupt
#                data before stb_image decodes it (stb_image reports none).
if(NOT TARGET seqslam_stb)
  find_path(SEQSLAM_STB_INCLUDE_DIR stb_image.h PATH_SUFFIXES stb
            DOC "Directory containing stb_image.h and stb_image_write.h")
  find_library(SEQSLAM_STB_LIBRARY NAMES stb DOC "libstb with the stb implementations")
  if(NOT SEQSLAM_STB_INCLUDE_DIR OR NOT SEQSLAM_STB_LIBRARY)
    message(FATAL_ERROR "stb not found (Debian/Ubuntu: apt-get install libstb-dev); set "
                        "SEQSLAM_STB_INCLUDE_DIR and SEQSLAM_STB_LIBRARY")
  endif()
  add_library(seqslam_stb UNKNOWN IMPORTED GLOBAL)
  set_target_properties(seqslam_stb PROPERTIES
    IMPORTED_LOCATION "${SEQSLAM_STB_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${SEQSLAM_STB_INCLUDE_DIR}")
endif()

if(NOT TARGET PNG::PNG)
  find_package(PNG)
  if(NOT PNG_FOUND)
    message(FATAL_ERROR "libpng not found (Debian/Ubuntu: apt-get install libpng-dev)")
  endif()
  set_target_properties(PNG::PNG PROPERTIES IMPORTED_GLOBAL TRUE)
  if(TARGET ZLIB::ZLIB)
    set_target_properties(ZLIB::ZLIB PROPERTIES IMPORTED_GLOBAL TRUE)
  endif()
endif()

if(NOT TARGET JPEG::JPEG)
  find_package(JPEG)
  if(NOT JPEG_FOUND)
    message(FATAL_ERROR "libjpeg not found (Debian/Ubuntu: apt-get install libjpeg-dev)")
  endif()
  set_target_properties(JPEG::JPEG PROPERTIES IMPORTED_GLOBAL TRUE)
endif()
