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
# The sanitized stage (ctest -L sanitized, `bash scripts/test --sanitized`) runs what sanitizers are
# for: readers, parsers and file formats, the predictor's hostile-stream handling, and the unit tests
# of memory-heavy code (OpenVDB removal, FE assembly and factorizations, clouds, k-d trees, voxel
# fields), each test about a minute at most under ASan on a loaded 2-core machine; no statistical
# study, no end-to-end run (those run in the Release build).
# drom_sanitized_tests(<test executable> <GoogleTest filter> <timeout s>): the timeout is at least 3x
# the slowest chosen test's time measured under ASan + UBSan while a Release build ran beside it on
# the same 2 cores (docs/building.md gives the table).
set(DROM_SANITIZED_TESTS "")
macro(drom_sanitized_tests executable filter timeout)
  list(APPEND DROM_SANITIZED_TESTS ${executable})
  set(DROM_SANITIZED_FILTER_${executable} "${filter}")
  set(DROM_SANITIZED_TIMEOUT_${executable} ${timeout})
endmacro()
drom_sanitized_tests(support_tests "*" 60)      # slowest 3.6 s: the PNG plot (a child process)
drom_sanitized_tests(case_file_tests "*" 60)         # 0.9 s
drom_sanitized_tests(reduce_tests "*" 60)       # 1.8 s
drom_sanitized_tests(machine_tests "*" 120)     # 11.1 s: LinuxCNC's milling samples through rs274
# Not the hole filling's six-draw ball study beside a step's wall (16 s in Release, over 120 s here).
drom_sanitized_tests(geometry_tests "-CloudHoles.ABallOnAStepsFilledScanDoesNotSinkBesideTheWallsTop" 120)  # 23.9 s: a STEP file that crashes OpenCASCADE
# Removal on small parts and the G-code reader; the plate at every voxel size, the panel's pocket,
# the graded plate and the hex-mesh convergence study run in the Release build.
drom_sanitized_tests(levelset_tests
  "SweptVolume.*:GCode.*:Toolpath.*:ToolGeometry.*:CutFraction.*:Removal.FlatPlatePocketRemovesItsVolume:Removal.GCodeRoundTripGivesSameStationsAndVolumes:Removal.SpiralAndZigzagPocketsClearThePocket:RemovalFraction.TetGenBlockWithAPocketIsExact:RemovalFraction.CutsInsideElementsConvergeAtSecondOrder"
  240)                                          # 55.7 s: the flat plate's pocket
# Elements, quadrature, patch tests, the factorizations and their block updates, the CalculiX deck;
# the layer-removal convergence studies run in the Release build.
drom_sanitized_tests(fem_tests
  "ShapeFunctions.*:Quadrature.*:PatchTest.*:IntactStock.*:Superposition.*:SpdSolver.*:TrailingBlockCholesky.*:BlockRefactorization.*:BlockPlan.*:CalculixDeck.*"
  120)                                          # 24.2 s: superposition of unit responses
# The cutter model; finishing's planners and case reader, not the swept-tool scallop studies (they run
# in the Release build); clouds (readers, k-d trees, normals, drop, packets, finishing).
drom_sanitized_tests(cutter_tests "*" 60)
drom_sanitized_tests(finish_tests
  "-ScallopBound.TheTorusKeepsItFedObliquelyToTheSlope:ScallopBound.RunOutsKeepItAtTheEdges:ScallopBound.CurvedStepoverKeepsItOnBothSurfacesWithBothTools:ScallopBound.RunOutsKeepItOnTheSeamsBetweenZones:Gouging.*"
  240)
drom_sanitized_tests(copy_tests "-CloudFinishing.SphereNoGougeAndScallopWithinTheBound"
  240)                                          # 58.3 s: cloud finishing on a free-form patch
# The axis relaxed under the limits, the axis dynamics, the voxel field's near field, the orient case reader's errors, two scenes.
drom_sanitized_tests(orient_tests
  "OrientationUnderLimits.*:AxisDynamics.*:AxisIntegrators.*:OrientBump.*:OrientScenes.*:OrientBadInput.*:OrientVoxelField.TheNearFieldIsExactWhereTheGridCannotFollow:OrientClearance.BumpIsCollisionFreeWithTheModelOnly:OrientClearance.ImpellerVeinWithATorusCutterIsCollisionFreeWithTheModelOnly"
  150)                                          # 39.9 s: the impeller's vein with a torus
# The predictor, its hostile stream, the sensor and the loop's machine; not the 200-draw coverage study.
drom_sanitized_tests(online_tests "-Predictor.NinetyFivePercentBandCoversTheTruthAtNinetyFivePercentOfNodes" 180)  # 45.0 s: ingest and queries at once
