# camera/sim: finds the CMU clips beside the source tree by default (../shared/data/mocap).
set_source_files_properties(${CMAKE_CURRENT_SOURCE_DIR}/sim/simulator.cpp PROPERTIES
  COMPILE_DEFINITIONS "YELAN_SOURCE_DIR=\"${PROJECT_SOURCE_DIR}\"")
# scene.json files
find_package(nlohmann_json 3 REQUIRED)
target_link_libraries(yelan_camera PUBLIC nlohmann_json::nlohmann_json)
