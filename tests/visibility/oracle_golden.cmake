# Golden visible areas against CGAL's exact Boolean set operations on random scenes.
add_executable(golden_oracle_tests ${CMAKE_CURRENT_LIST_DIR}/golden_oracle_tests.cpp)
target_link_libraries(golden_oracle_tests PRIVATE tilevis_visibility tilevis_cgal_oracle tilevis_warnings GTest::gtest_main)
gtest_discover_tests(golden_oracle_tests DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 600)
