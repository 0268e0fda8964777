# Every module folder builds one static library, drom_<module>, exported as drom::<module>. Its headers
# are installed under include/drom/<module>/, so code outside the tree includes them as inside it:
# #include "offline/offline_job.hpp" with include/drom on the include path.
include(GNUInstallDirs)

function(drom_library module)
  set(target drom_${module})
  add_library(${target} STATIC ${ARGN})
  add_library(drom::${module} ALIAS ${target})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/drom>)
  # Position-independent, so the Python module (a shared object) can link every library.
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${module} POSITION_INDEPENDENT_CODE ON)
  install(TARGETS ${target} EXPORT dromTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  # Headers keep their place in the tree (paths/finish/... for the target paths_finish), so an
  # installed #include "paths/finish/finish_run.hpp" reads as it does here.
  file(RELATIVE_PATH folder ${PROJECT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR})
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/drom/${folder} FILES_MATCHING PATTERN "*.hpp")
endfunction()
