# The layers read core <- port <- {runtime, hal} <- app: each layer's headers and sources
# include the rgbdtam headers of its own layer and the layers below it, never one beside or
# above it. Fails naming every include that breaks this.
#   cmake -DSRC=<repo> -P tools/check_layers.cmake
cmake_minimum_required(VERSION 3.16)
set(_allowed_core core)
set(_allowed_port core port)
set(_allowed_runtime core port runtime)
set(_allowed_hal core port hal)

set(_broken 0)
foreach(layer core port runtime hal)
  file(GLOB_RECURSE _files ${SRC}/include/rgbdtam/${layer}/*.hpp ${SRC}/src/${layer}/*.cpp
       ${SRC}/src/${layer}/*.hpp)
  if(NOT _files)
    message(FATAL_ERROR "layer ${layer}: no files under ${SRC}")
  endif()
  foreach(file ${_files})
    file(STRINGS ${file} _includes REGEX "^#include \"rgbdtam/[a-z_]+/")
    foreach(line ${_includes})
      string(REGEX REPLACE "^#include \"rgbdtam/([a-z_]+)/.*" "\\1" _target "${line}")
      if(NOT _target IN_LIST _allowed_${layer})
        file(RELATIVE_PATH _rel ${SRC} ${file})
        message(SEND_ERROR "${_rel} (${layer}) includes ${_target}: ${line}")
        math(EXPR _broken "${_broken} + 1")
      endif()
    endforeach()
  endforeach()
endforeach()
if(_broken GREATER 0)
  message(FATAL_ERROR "${_broken} includes break the layers core <- port <- {runtime, hal} <- app")
endif()
message(STATUS "layers: core <- port <- {runtime, hal} <- app holds")
