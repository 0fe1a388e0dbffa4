// Host of the test programs' shared precompiled header (tests/CMakeLists.txt: ident_test_pch):
// CMake needs one source to build the header with the test programs' flags; it defines nothing.
