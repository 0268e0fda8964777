# -DDROM_FUZZ=ON (clang only; docs/robustness.md): the whole tree is built with AddressSanitizer and
# UndefinedBehaviorSanitizer, and with libFuzzer's coverage instrumentation, so one build serves the
# fuzz harnesses (fuzz/) and the sanitized test subset (ctest -L sanitized). Any UB aborts.
if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  message(FATAL_ERROR "DROM_FUZZ needs clang (libFuzzer): CC=clang CXX=clang++ cmake -DDROM_FUZZ=ON ... (scripts/fuzz does this)")
endif()
add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all -fsanitize=fuzzer-no-link -fno-omit-frame-pointer -g
                    -fsanitize-ignorelist=${CMAKE_CURRENT_LIST_DIR}/sanitizer_ignorelist.txt
                    -fsanitize-coverage-ignorelist=${CMAKE_CURRENT_LIST_DIR}/fuzz_coverage_ignorelist.txt)
add_link_options(-fsanitize=address,undefined)
# OpenCASCADE's blocks kept until exit are not drom's leaks (cmake/lsan_suppressions.txt).
set(DROM_LSAN_OPTIONS LSAN_OPTIONS=suppressions=${CMAKE_CURRENT_LIST_DIR}/lsan_suppressions.txt:print_suppressions=0)
# An instrumented Python module would need ASan preloaded into python: not built here.
set(DROM_PYTHON OFF CACHE BOOL "Build the drom Python module" FORCE)
# The test executables that run sanitized (tests/CMakeLists.txt labels their tests "sanitized"):
# the readers' and the predictor's modules (support, case, reduce, online); levelset and fem (OpenVDB
# removal, FE solves) are left out to keep CI short, and the end-to-end tests run the drom binary.
set(DROM_SANITIZED_TESTS support_tests case_tests reduce_tests online_tests)
