# Hybrid visibility against the z-buffer truth on interpenetrating, blended and overloaded scenes.
add_executable(hybrid_tests ${CMAKE_CURRENT_LIST_DIR}/hybrid_tests.cpp)
target_link_libraries(hybrid_tests PRIVATE tilevis_visibility tilevis_scene tilevis_warnings GTest::gtest_main)
gtest_discover_tests(hybrid_tests DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 900)
