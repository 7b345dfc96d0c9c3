# soadyn_peer_plugin(TARGET SOURCE LIBS...): tools/bench/SOURCE built as the plugin TARGET that
# soadyn_bench loads (peer.hpp).  Its symbols are hidden but for the two entry points, so the
# peer's inline Eigen code (other alignment, other flags) binds within the plugin and never mixes
# with soadyn's.  -O3 -march=native, as ../shared/peers/build_peers.sh builds the peers.
# Used by peers.cmake and by the standalone project in peers/ (a peer built with another compiler).
function(soadyn_peer_plugin target source)
  add_library(${target} MODULE ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/${source})
  set_target_properties(${target} PROPERTIES CXX_STANDARD 17 CXX_VISIBILITY_PRESET hidden
                        VISIBILITY_INLINES_HIDDEN ON)
  target_include_directories(${target} PRIVATE ${CMAKE_CURRENT_FUNCTION_LIST_DIR})
  # GCC 12 warns inside its AVX-512 intrinsics when Pinocchio's joint code is inlined there
  target_compile_options(${target} PRIVATE -O3 -march=native $<$<CXX_COMPILER_ID:GNU>:-Wno-stringop-overread>)
  target_compile_definitions(${target} PRIVATE
    SOADYN_PEER_COMPILER="${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER_VERSION}")
  target_link_libraries(${target} PRIVATE ${ARGN})
  target_link_options(${target} PRIVATE -Wl,--no-undefined)
endfunction()
