# Embeds the OpenCL C sources of kernels/ into the binary, in the manner of OpenCV's
# cl2cpp.cmake: the .cl files stay valid OpenCL C; a generated .cc holds each one as a
# string, keyed by file name, and is rewritten only when a source changes.
function(hairmvs_embed_kernels target)
  cmake_parse_arguments(ARG "" "" "SOURCES" ${ARGN})
  set(out_cc "${CMAKE_CURRENT_BINARY_DIR}/embedded_kernels.cc")
  add_custom_command(
    OUTPUT ${out_cc}
    COMMAND ${CMAKE_COMMAND} -DOUTPUT=${out_cc} "-DSOURCES=${ARG_SOURCES}"
            -P ${PROJECT_SOURCE_DIR}/cmake/EmbedKernelsScript.cmake
    DEPENDS ${ARG_SOURCES} ${PROJECT_SOURCE_DIR}/cmake/EmbedKernelsScript.cmake
    COMMENT "Embedding OpenCL kernels"
    VERBATIM)
  add_library(${target} STATIC ${out_cc} ${PROJECT_SOURCE_DIR}/kernels/embedded_kernels.h)
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
endfunction()
