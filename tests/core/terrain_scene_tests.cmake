# Terrain and scene-loader tests; include()d from tests/core/CMakeLists.txt.
# yaml-cpp is linked directly because test_scene.cc uses core/yaml_util.h
# (quasiroll::core links yaml-cpp privately).
quasiroll_add_test(test_terrain test_terrain.cc LIBS quasiroll::core)
quasiroll_add_test(test_scene test_scene.cc LIBS quasiroll::core yaml-cpp)
