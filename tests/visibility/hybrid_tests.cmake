# Hybrid visibility against the z-buffer truth on interpenetrating, blended and overloaded scenes.
add_executable(hybrid_tests ${CMAKE_CURRENT_LIST_DIR}/hybrid_tests.cpp)
target_link_libraries(hybrid_tests PRIVATE tilevis_visibility tilevis_test_scenes tilevis_warnings GTest::gtest_main)
gtest_discover_tests(hybrid_tests DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 900)

# The failure scenes (traces/scenes): hybrid equals the truth through the CLI at 16, 32 and 128.
if(TARGET tilevis)
  # COST: 6 to 21 s each in CI under the sanitizers, so CTest starts them first
  # (tests/report/CMakeLists.txt says why).
  foreach(scene interpenetrating decals glass broken_mesh slivers hot_tile)
    add_test(NAME hybrid_scene_${scene}
             COMMAND ${CMAKE_CURRENT_LIST_DIR}/hybrid_scene.sh $<TARGET_FILE:tilevis>
                     ${PROJECT_SOURCE_DIR}/traces/scenes/${scene}.json ${CMAKE_CURRENT_BINARY_DIR}/hybrid_scenes 16 32 128)
    set_tests_properties(hybrid_scene_${scene} PROPERTIES TIMEOUT 600 COST 10)
  endforeach()
endif()

# The public SVGPU functions on hand-made cases.
add_executable(svgpu_tests ${CMAKE_CURRENT_LIST_DIR}/svgpu_tests.cpp)
target_link_libraries(svgpu_tests PRIVATE tilevis_visibility tilevis_warnings GTest::gtest_main)
gtest_discover_tests(svgpu_tests DISCOVERY_TIMEOUT 60)

# The per-tile visibility interface: registry, per_pixel = truth, records, tile order.
add_executable(tile_resolver_tests ${CMAKE_CURRENT_LIST_DIR}/tile_resolver_tests.cpp)
target_link_libraries(tile_resolver_tests PRIVATE tilevis_visibility tilevis_test_scenes tilevis_warnings GTest::gtest_main)
gtest_discover_tests(tile_resolver_tests DISCOVERY_TIMEOUT 60)
