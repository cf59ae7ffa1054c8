# `cmake --install` (issue 12, item 8): the module libraries, their headers and a CementSPHConfig.cmake,
# so that another project can `find_package(CementSPH)` and link CementSPH::SPH, CementSPH::ImagingIO, ...
# One file instead of rules spread over the modules: the modules keep building exactly as before.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CEMENTSPH_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/CementSPH)

# Library target -> the name it has after CementSPH:: (as the in-tree aliases).
set(CEMENTSPH_EXPORTED_LIBRARIES
  CementSPH_Provenance:Provenance CementSPH_SPH:SPH CementSPH_VoxelDarcy:VoxelDarcy CementSPH_Rendering:Rendering CementSPH_SurfaceMetrics:SurfaceMetrics
  CementSPH_ImagingIO:ImagingIO CementSPH_Registration:Registration CementSPH_Segmentation:Segmentation
  CementSPH_Anatomy:Anatomy CementSPH_Scene:Scene CementSPH_CTScene:CTScene CementSPH_Phantom:Phantom CementSPH_Study:Study
  CementSPH_Planning:Planning CementSPH_Parallel:Parallel
  CementSPH_DRR:DRR CementSPH_Pipeline:Pipeline
  # Static libraries carry their private usage requirements into the export ($<LINK_ONLY:...>), so the
  # two interface targets of compile flags go along (they add nothing to a consumer's link).
  cementsph_warnings:warnings cementsph_optimise:optimise)

set(_cementsph_targets)
foreach(entry IN LISTS CEMENTSPH_EXPORTED_LIBRARIES)
  string(REPLACE ":" ";" pair "${entry}")
  list(GET pair 0 target)
  list(GET pair 1 exportName)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${exportName})
  list(APPEND _cementsph_targets ${target})
  # Each module names its own include/ folder (absolute, in the source tree): in the installed package
  # the headers of every module sit together under include/.
  get_target_property(includes ${target} INTERFACE_INCLUDE_DIRECTORIES)
  if(includes)
    set(relocated)
    foreach(dir IN LISTS includes)
      if(dir MATCHES "^${PROJECT_SOURCE_DIR}/")
        list(APPEND relocated "$<BUILD_INTERFACE:${dir}>")
      else()
        list(APPEND relocated "${dir}")
      endif()
    endforeach()
    list(APPEND relocated "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>")
    set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${relocated}")
  endif()
endforeach()

install(TARGETS ${_cementsph_targets} EXPORT CementSPHTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
file(GLOB _cementsph_include_dirs LIST_DIRECTORIES true ${PROJECT_SOURCE_DIR}/Modules/*/*/include)
foreach(dir IN LISTS _cementsph_include_dirs)
  install(DIRECTORY ${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endforeach()
install(EXPORT CementSPHTargets NAMESPACE CementSPH:: DESTINATION ${CEMENTSPH_INSTALL_CMAKEDIR})

# What the config must find again for the exported usage requirements (CementSPHDependencies.cmake and
# the Rendering module): the same packages, with the same VTK and ITK components.
set(CEMENTSPH_CONFIG_VTK_COMPONENTS ${CEMENTSPH_VTK_COMPONENTS})
set(CEMENTSPH_CONFIG_ITK_COMPONENTS ${CEMENTSPH_ITK_COMPONENTS})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/CementSPHConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/CementSPHConfig.cmake
  INSTALL_DESTINATION ${CEMENTSPH_INSTALL_CMAKEDIR})
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/CementSPHConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/CementSPHConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/CementSPHConfigVersion.cmake
  DESTINATION ${CEMENTSPH_INSTALL_CMAKEDIR})
