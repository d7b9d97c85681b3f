// The precompiled header of the test programs is built with this unit (tests/CMakeLists.txt,
// rhot_test_pch); it has no code of its own.
