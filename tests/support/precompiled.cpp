// The translation unit that builds the test files' precompiled header (tests/CMakeLists.txt,
// TESSERA_TEST_PCH); it has no code of its own.
