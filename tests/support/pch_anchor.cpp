// The one source of medspring_test_pch (tests/CMakeLists.txt): CMake builds the tests' shared
// precompiled header with this target's flags; the object itself is linked into nothing.
