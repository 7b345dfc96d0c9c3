# `soadyn view`: its sources, and the page's assets (template, script, three.js) compiled into the
# executable, so the page it writes needs nothing at run time.  three.js is Debian's libjs-three.
find_file(SOADYN_THREE_JS three.min.js PATHS /usr/share/javascript/three NO_DEFAULT_PATH
          DOC "three.js, minified (Debian libjs-three)")
find_file(SOADYN_ORBIT_JS OrbitControls.js PATHS /usr/share/javascript/three/examples/js/controls NO_DEFAULT_PATH
          DOC "three.js OrbitControls, the UMD build (Debian libjs-three)")
if(NOT SOADYN_THREE_JS OR NOT SOADYN_ORBIT_JS)
  message(FATAL_ERROR "three.js not found: install Debian's libjs-three (tools/setup.sh does), "
                      "or give -DSOADYN_THREE_JS=<three.min.js> -DSOADYN_ORBIT_JS=<OrbitControls.js>")
endif()
set(_view ${CMAKE_CURRENT_SOURCE_DIR}/tools/view)
set(_assets "page_html=${_view}/viewer.html|page_css=${_view}/viewer.css|page_js=${_view}/viewer.js|plot_js=${_view}/plot.js|frames_js=${_view}/frames.js|bodies_js=${_view}/bodies.js|three_js=${SOADYN_THREE_JS}|orbit_js=${SOADYN_ORBIT_JS}")
set(_assets_cpp ${CMAKE_CURRENT_BINARY_DIR}/view_assets.cpp)
add_custom_command(OUTPUT ${_assets_cpp}
  COMMAND ${CMAKE_COMMAND} -DOUT=${_assets_cpp} "-DASSETS=${_assets}" -P ${_view}/embed.cmake
  DEPENDS ${_view}/embed.cmake ${_view}/viewer.html ${_view}/viewer.css ${_view}/viewer.js ${_view}/plot.js ${_view}/frames.js ${_view}/bodies.js ${SOADYN_THREE_JS} ${SOADYN_ORBIT_JS}
  COMMENT "Embedding the viewer's page and three.js" VERBATIM)
target_sources(soadyn_cli PRIVATE src/cli/view.cpp src/cli/view_run.cpp src/cli/view_scene.cpp ${_assets_cpp})
target_link_libraries(soadyn_cli PRIVATE yaml-cpp ${urdfdom_LIBRARIES})
target_include_directories(soadyn_cli SYSTEM PRIVATE ${urdfdom_INCLUDE_DIRS})
