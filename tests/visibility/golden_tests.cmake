# Golden pipeline, z-buffer truth and primitive setup, on small scenes built in-process.
add_executable(visibility_tests ${CMAKE_CURRENT_LIST_DIR}/visibility_tests.cpp)
target_link_libraries(visibility_tests PRIVATE tilevis_visibility tilevis_test_scenes tilevis_warnings GTest::gtest_main)
gtest_discover_tests(visibility_tests DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 900)
