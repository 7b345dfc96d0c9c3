# The libraries soadyn_bench times beside soadyn (tools/bench/bench_peers.cpp), each built as a
# plugin (tools/bench/peer.hpp) that soadyn_bench loads at run time:
#   mujoco           when installed (MUJOCO_INCLUDE_DIR, MUJOCO_LIBRARY found by the caller);
#   pinocchio        its CMake package under SOADYN_PEERS_PREFIX, compiled by this compiler;
#   pinocchio-clang  its CMake package under SOADYN_PEERS_CLANG_PREFIX (default PREFIX-clang),
#                    compiled by clang++ (tools/bench/peers/CMakeLists.txt);
#   rbdl             rbdl + rbdl_urdfreader under SOADYN_PEERS_PREFIX.
# ../shared/peers/build_peers.sh builds Pinocchio and RBDL outside the repository with -O3
# -march=native (into /tmp/peerbuild/install); their plugins are compiled with the same flags.  A
# peer that is not found is left out with one note, at configure time and in the benchmark output.
set(SOADYN_PEERS_PREFIX "" CACHE PATH "Install prefix of Pinocchio and RBDL, timed as benchmark peers")

target_sources(soadyn_bench PRIVATE tools/bench/bench_peers.cpp)
target_link_libraries(soadyn_bench PRIVATE ${CMAKE_DL_LIBS})
set(_soadyn_peers "")
set(_soadyn_peers_note "")

include(tools/bench/peer_plugin.cmake)
# soadyn_bench_peer(NAME LIBS...): tools/bench/peer_NAME.cpp as the plugin soadyn_peer_NAME
function(soadyn_bench_peer name)
  soadyn_peer_plugin(soadyn_peer_${name} peer_${name}.cpp ${ARGN})
  add_dependencies(soadyn_bench soadyn_peer_${name})
  list(APPEND _soadyn_peers "${name}=$<TARGET_FILE:soadyn_peer_${name}>")
  set(_soadyn_peers "${_soadyn_peers}" PARENT_SCOPE)
endfunction()
function(soadyn_bench_peer_missing text)
  message(STATUS "Benchmark peer left out: ${text}")
  if(_soadyn_peers_note)
    set(text "${_soadyn_peers_note} / ${text}")  # not "; ": CMake would split the definition there
  endif()
  set(_soadyn_peers_note "${text}" PARENT_SCOPE)
endfunction()

if(MUJOCO_INCLUDE_DIR AND MUJOCO_LIBRARY)
  message(STATUS "Benchmark peer: MuJoCo (${MUJOCO_LIBRARY})")
  soadyn_bench_peer(mujoco ${MUJOCO_LIBRARY})
  target_include_directories(soadyn_peer_mujoco SYSTEM PRIVATE ${MUJOCO_INCLUDE_DIR})
else()
  soadyn_bench_peer_missing("MuJoCo not installed (apt-get install libmujoco-dev)")
endif()

if(NOT SOADYN_PEERS_PREFIX)
  soadyn_bench_peer_missing("Pinocchio and RBDL (no -DSOADYN_PEERS_PREFIX)")
else()
  # earlier configure runs' results are dropped: the prefix may have changed
  unset(pinocchio_DIR CACHE)
  foreach(v SOADYN_RBDL_INCLUDE_DIR SOADYN_RBDL_LIBRARY SOADYN_RBDL_URDF_LIBRARY)
    unset(${v} CACHE)
  endforeach()
  find_package(pinocchio CONFIG QUIET PATHS ${SOADYN_PEERS_PREFIX} NO_DEFAULT_PATH)
  if(pinocchio_FOUND)
    message(STATUS "Benchmark peer: Pinocchio ${pinocchio_VERSION} from ${SOADYN_PEERS_PREFIX}")
    soadyn_bench_peer(pinocchio pinocchio::pinocchio)
  else()
    soadyn_bench_peer_missing("Pinocchio not found in ${SOADYN_PEERS_PREFIX}")
  endif()
  # Pinocchio compiled by clang (much faster than by g++), when build_peers.sh's CLANG=1 build sits
  # beside the prefix: a separate project, so that clang++ compiles it
  set(SOADYN_PEERS_CLANG_PREFIX "" CACHE PATH
      "Install prefix of Pinocchio built by clang, timed as pinocchio-clang (empty: SOADYN_PEERS_PREFIX-clang)")
  set(_clang_prefix "${SOADYN_PEERS_CLANG_PREFIX}")
  if(NOT _clang_prefix)
    set(_clang_prefix "${SOADYN_PEERS_PREFIX}-clang")
  endif()
  find_program(SOADYN_CLANGXX NAMES clang++ clang++-14)
  if(EXISTS ${_clang_prefix}/lib/cmake/pinocchio AND SOADYN_CLANGXX)
    message(STATUS "Benchmark peer: Pinocchio compiled by ${SOADYN_CLANGXX} from ${_clang_prefix}")
    include(ExternalProject)
    set(_dir ${CMAKE_BINARY_DIR}/peer_pinocchio_clang)
    ExternalProject_Add(soadyn_peer_pinocchio_clang
      SOURCE_DIR ${CMAKE_CURRENT_SOURCE_DIR}/tools/bench/peers BINARY_DIR ${_dir}
      CMAKE_ARGS -DCMAKE_CXX_COMPILER=${SOADYN_CLANGXX} -DCMAKE_BUILD_TYPE=Release
                 -DPEERS_PREFIX=${_clang_prefix}
      BUILD_ALWAYS ON INSTALL_COMMAND "" BUILD_BYPRODUCTS ${_dir}/libsoadyn_peer_pinocchio.so)
    add_dependencies(soadyn_bench soadyn_peer_pinocchio_clang)
    list(APPEND _soadyn_peers "pinocchio-clang=${_dir}/libsoadyn_peer_pinocchio.so")
  else()
    soadyn_bench_peer_missing("Pinocchio compiled by clang (not in ${_clang_prefix}, or no clang++)")
  endif()
  # RBDL installs no CMake targets to rely on: its files are found directly
  find_path(SOADYN_RBDL_INCLUDE_DIR rbdl/rbdl.h PATHS ${SOADYN_PEERS_PREFIX}/include NO_DEFAULT_PATH)
  find_library(SOADYN_RBDL_LIBRARY rbdl PATHS ${SOADYN_PEERS_PREFIX}/lib NO_DEFAULT_PATH)
  find_library(SOADYN_RBDL_URDF_LIBRARY rbdl_urdfreader PATHS ${SOADYN_PEERS_PREFIX}/lib NO_DEFAULT_PATH)
  if(SOADYN_RBDL_INCLUDE_DIR AND SOADYN_RBDL_LIBRARY AND SOADYN_RBDL_URDF_LIBRARY)
    message(STATUS "Benchmark peer: RBDL (${SOADYN_RBDL_LIBRARY})")
    soadyn_bench_peer(rbdl ${SOADYN_RBDL_URDF_LIBRARY} ${SOADYN_RBDL_LIBRARY} Eigen3::Eigen)
    target_include_directories(soadyn_peer_rbdl SYSTEM PRIVATE ${SOADYN_RBDL_INCLUDE_DIR})
  else()
    soadyn_bench_peer_missing("RBDL with its URDF reader not found in ${SOADYN_PEERS_PREFIX}")
  endif()
endif()

string(JOIN "," _soadyn_peers_list ${_soadyn_peers})
target_compile_definitions(soadyn_bench PRIVATE "SOADYN_BENCH_PEERS=\"${_soadyn_peers_list}\""
                           "SOADYN_BENCH_PEERS_NOTE=\"${_soadyn_peers_note}\"")
