# `soadyn view`: its sources, and the page's assets (template, script, three.js and its mesh
# loaders) compiled into the executable, so the page it writes needs nothing at run time.
# three.js is Debian's libjs-three (r111); its STL, OBJ and Collada loaders are the UMD builds the
# same package ships (they attach to THREE, and match the three.min.js inlined beside them).
set(_three /usr/share/javascript/three)
find_file(SOADYN_THREE_JS three.min.js PATHS ${_three} NO_DEFAULT_PATH
          DOC "three.js, minified (Debian libjs-three)")
find_file(SOADYN_ORBIT_JS OrbitControls.js PATHS ${_three}/examples/js/controls NO_DEFAULT_PATH
          DOC "three.js OrbitControls, the UMD build (Debian libjs-three)")
find_file(SOADYN_STL_JS STLLoader.js PATHS ${_three}/examples/js/loaders NO_DEFAULT_PATH
          DOC "three.js STLLoader, the UMD build (Debian libjs-three)")
find_file(SOADYN_OBJ_JS OBJLoader.js PATHS ${_three}/examples/js/loaders NO_DEFAULT_PATH
          DOC "three.js OBJLoader, the UMD build (Debian libjs-three)")
find_file(SOADYN_COLLADA_JS ColladaLoader.js PATHS ${_three}/examples/js/loaders NO_DEFAULT_PATH
          DOC "three.js ColladaLoader, the UMD build (Debian libjs-three)")
if(NOT SOADYN_THREE_JS OR NOT SOADYN_ORBIT_JS OR NOT SOADYN_STL_JS OR NOT SOADYN_OBJ_JS OR NOT SOADYN_COLLADA_JS)
  message(FATAL_ERROR "three.js not found: install Debian's libjs-three (tools/setup.sh does), or give "
                      "-DSOADYN_THREE_JS=<three.min.js> -DSOADYN_ORBIT_JS=<OrbitControls.js> -DSOADYN_STL_JS=<STLLoader.js> "
                      "-DSOADYN_OBJ_JS=<OBJLoader.js> -DSOADYN_COLLADA_JS=<ColladaLoader.js> (the same three.js release)")
endif()
set(_view ${CMAKE_CURRENT_SOURCE_DIR}/tools/view)
set(_pieces viewer.html viewer.css viewer.js plot.js frames.js meshes.js bodies.js)
set(_assets "page_html=${_view}/viewer.html|page_css=${_view}/viewer.css|page_js=${_view}/viewer.js|plot_js=${_view}/plot.js|frames_js=${_view}/frames.js|meshes_js=${_view}/meshes.js|bodies_js=${_view}/bodies.js")
string(APPEND _assets "|three_js=${SOADYN_THREE_JS}|orbit_js=${SOADYN_ORBIT_JS}|stl_js=${SOADYN_STL_JS}|obj_js=${SOADYN_OBJ_JS}|collada_js=${SOADYN_COLLADA_JS}")
list(TRANSFORM _pieces PREPEND ${_view}/)
set(_assets_cpp ${CMAKE_CURRENT_BINARY_DIR}/view_assets.cpp)
add_custom_command(OUTPUT ${_assets_cpp}
  COMMAND ${CMAKE_COMMAND} -DOUT=${_assets_cpp} "-DASSETS=${_assets}" -P ${_view}/embed.cmake
  DEPENDS ${_view}/embed.cmake ${_pieces} ${SOADYN_THREE_JS} ${SOADYN_ORBIT_JS} ${SOADYN_STL_JS} ${SOADYN_OBJ_JS} ${SOADYN_COLLADA_JS}
  COMMENT "Embedding the viewer's page, three.js and its mesh loaders" VERBATIM)
target_sources(soadyn_cli PRIVATE src/cli/view.cpp src/cli/view_run.cpp src/cli/view_scene.cpp src/cli/view_meshes.cpp ${_assets_cpp})
target_link_libraries(soadyn_cli PRIVATE yaml-cpp ${urdfdom_LIBRARIES})
target_include_directories(soadyn_cli SYSTEM PRIVATE ${urdfdom_INCLUDE_DIRS})
