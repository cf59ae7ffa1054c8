# The GoogleTest suites live beside their modules (Modules/<Group>/<Module>/test, Applications/cementsph/test
# for the suites that run the cementsph program), as ITK's do; each test/CMakeLists.txt names its suites and
# their ctest labels. Testing/ keeps what crosses modules: the shared support code (Testing/Support), the fuzz
# suite, the install consumers, the Python tests and the benchmarks.
# Labels: unit (fast, exact), validation (physics against an oracle), render (off-screen pictures), install,
# slow (skipped by the quick run: ctest -LE slow). slow goes, beside the suite's own label, on every suite whose
# tests took over 10 s together in a serial ctest run (measured 2026-12-01 on the shared 2-core machine at load
# 5-10, so times are high): SPHDarcyValidationTest 414 s, DemoCommandTest 24 s, ComparePicturesTest 20.5 s,
# CompareCommandTest 19.6 s, StudyRunnerTest 15.8 s, AffineRegistrationTest 15.6 s, PhantomReproducibilityTest
# 10.5 s; the next, StudyCommandTest, 7.7 s. How many tests there are, and how many the quick run holds, is
# what `ctest -N` and `ctest -N -LE slow` print.
include(GoogleTest)

# Test-support code shared by suites of several modules (ProgramRun.h, ScaffoldCT.h, RenderingTestSupport.h, ...).
set(CEMENTSPH_TEST_SUPPORT_DIR ${PROJECT_SOURCE_DIR}/Testing/Support)
# Reference pictures of the render suites (see Testing/Data/Baselines/README.md).
set(CEMENTSPH_TEST_BASELINE_DIR ${PROJECT_SOURCE_DIR}/Testing/Data/Baselines)

# cementsph_add_gtest(<name> SOURCES ... LIBS ... LABELS ... [TIMEOUT s] [PROGRAM])
# PROGRAM: the suite runs the cementsph program, whose path it gets as CEMENTSPH_EXECUTABLE (TestPaths.h), and is
# built after it.
function(cementsph_add_gtest name)
  cmake_parse_arguments(T "PROGRAM" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${T_SOURCES})
  if(T_PROGRAM)
    add_dependencies(${name} cementsph)
  endif()
  target_link_libraries(${name} PRIVATE GTest::gtest GTest::gtest_main ${T_LIBS} cementsph_test_paths
    CementSPH::warnings)
  target_include_directories(${name} PRIVATE ${CEMENTSPH_TEST_SUPPORT_DIR})
  # The paths (CEMENTSPH_TEST_DATA_DIR, CEMENTSPH_BINARY_DIR, CEMENTSPH_EXECUTABLE) come from TestPaths.h, found on
  # the include path above: no absolute path on the suite's compile line, so ccache hits in a clone at another path.
  target_compile_options(${name} PRIVATE -include TestPaths.h)
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 600)
  endif()
  # Passive OpenMP waiting: tests are not timed, and spinning barriers make a test many times slower
  # when something else holds a core (measured: a 0.3 s unit test took 25 s next to a compile).
  # gtest_discover_tests flattens PROPERTIES, so a second label (e.g. "validation slow") would become a property
  # name and swallow TIMEOUT: the first label goes with the properties, and all of them are set afterwards by
  # a script ctest includes once the discovered tests (listed in ${name}_TESTS) exist.
  list(GET T_LABELS 0 firstLabel)
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST
    PROPERTIES LABELS "${firstLabel}" TIMEOUT ${T_TIMEOUT} ENVIRONMENT "OMP_WAIT_POLICY=PASSIVE")
  list(LENGTH T_LABELS labelCount)
  if(labelCount GREATER 1)
    set(labelsScript "${CMAKE_CURRENT_BINARY_DIR}/${name}_labels.cmake")
    file(WRITE "${labelsScript}"
      "if(DEFINED ${name}_TESTS)\n  set_tests_properties(\${${name}_TESTS} PROPERTIES LABELS \"${T_LABELS}\")\nendif()\n")
    set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${labelsScript}")
  endif()
endfunction()
