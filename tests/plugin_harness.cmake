# The plugin driven in-process by MeshLab's own PluginManager (integration/plugin_harness.cpp),
# for the MeshLab the plugin is built for. MeshLab 2022+ also runs every shipped .mlx the way its
# Filter Script dialog does.
add_executable(plugin_harness integration/plugin_harness.cpp integration/harness_meshlab.h)
target_link_libraries(plugin_harness PRIVATE vcg_plylib meshlab_common)
set_target_properties(plugin_harness PROPERTIES BUILD_RPATH "${MESHLAB_LIBDIR}" AUTOMOC OFF)
set(_harness_args "$<TARGET_FILE:filter_conelod>" "${CONELOD_TEST_MESHES}/stanford_bunny_bun_zipper.ply"
    "${PROJECT_SOURCE_DIR}/test_meshes/nan_vertex.ply" --digest "${PROJECT_BINARY_DIR}/plugin_digest.txt")
if(MESHLAB_API GREATER_EQUAL 2022)
  list(APPEND _harness_args --scripts "${PROJECT_SOURCE_DIR}/scripts/mlx")
endif()
add_test(NAME it_plugin_harness COMMAND plugin_harness ${_harness_args})
set_tests_properties(it_plugin_harness PROPERTIES LABELS integration TIMEOUT 600
                     ENVIRONMENT "QT_QPA_PLATFORM=offscreen;XDG_RUNTIME_DIR=${PROJECT_BINARY_DIR};QT_LOGGING_RULES=*.debug=false")
