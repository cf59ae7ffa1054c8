# `cmake --install` (issue 12, item 8; componentised in issue 22, item 3): the module libraries, their headers
# and a CementSPHConfig.cmake, so that another project can
#   find_package(CementSPH REQUIRED COMPONENTS SPH DRR ...)
# and link CementSPH::SPH, CementSPH::DRR, ... Each module is one component with its own exported targets file
# (CementSPH<Module>Targets.cmake) and its own include folder (include/CementSPH/<Module>), and the config finds
# only the third-party packages of the components asked for (and of the components they link, transitively):
# SPH alone needs Eigen and OpenMP, not VTK, ITK or MPI.
# What each component needs is read here from the targets' link libraries, so a link dependency added in a
# module's CMakeLists.txt reaches the package without an edit here (a package not in the map below is named
# in a configure warning). One file instead of rules spread over the modules: the modules build as before.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CEMENTSPH_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/CementSPH)

# The components: every library target named CementSPH_<component> defined under Modules/ (each module's
# CMakeLists.txt, in add_subdirectory order), exported as CementSPH::<component> like its in-tree alias. A new
# module joins the package without an edit here.
function(_cementsph_module_libraries outVar)
  set(result)
  set(directories ${PROJECT_SOURCE_DIR})
  while(directories)
    list(POP_FRONT directories directory)
    get_property(subdirectories DIRECTORY ${directory} PROPERTY SUBDIRECTORIES)
    list(APPEND directories ${subdirectories})
    string(FIND "${directory}/" "${PROJECT_SOURCE_DIR}/Modules/" at) # a prefix test (paths may hold regex characters)
    if(NOT at EQUAL 0)
      continue()
    endif()
    get_property(targets DIRECTORY ${directory} PROPERTY BUILDSYSTEM_TARGETS)
    foreach(target IN LISTS targets)
      get_target_property(type ${target} TYPE)
      if(type MATCHES "^(STATIC|SHARED)_LIBRARY$" AND target MATCHES "^CementSPH_(.+)$")
        list(APPEND result "${target}:${CMAKE_MATCH_1}") # CMAKE_MATCH_1: the last MATCHES' group
      endif()
    endforeach()
  endwhile()
  set(${outVar} ${result} PARENT_SCOPE)
endfunction()
_cementsph_module_libraries(CEMENTSPH_EXPORTED_LIBRARIES)
# Static libraries carry their private usage requirements into the export ($<LINK_ONLY:...>), so the two
# interface targets of compile flags go along in a file every component loads (they add nothing to a
# consumer's compile or link).
set(CEMENTSPH_BUILD_FLAG_TARGETS cementsph_warnings:warnings cementsph_optimise:optimise)

# Third-party imported targets -> the package that defines them in a consumer (the config finds it again).
# ITK's own libraries are plain names (ITKCommon, itksys, itkvnl, ...) and GDCM's come with ITK's config.
function(_cementsph_package_of item outPackage)
  set(package "")
  if(item MATCHES "^VTK::")
    set(package VTK)
  elseif(item MATCHES "^(ITK|itk|gdcm)" OR item MATCHES "^ITKInternalEigen3::")
    set(package ITK)
  elseif(item MATCHES "^Eigen3::")
    set(package Eigen3)
  elseif(item MATCHES "^OpenMP::")
    set(package OpenMP)
  elseif(item MATCHES "^nlohmann_json::")
    set(package nlohmann_json)
  elseif(item MATCHES "^NLopt::")
    set(package NLopt)
  elseif(item MATCHES "^MPI::")
    set(package MPI)
  elseif(item MATCHES "^X11::")
    set(package X11)
  elseif(item MATCHES "^OpenGL::")
    set(package OpenGL)
  elseif(item MATCHES "^Threads::")
    set(package Threads)
  elseif(item MATCHES "^CLI11::")
    set(package CLI11)
  endif()
  set(${outPackage} "${package}" PARENT_SCOPE)
endfunction()

# Whether find_package(VTK COMPONENTS <module>) needs the C language in a consumer. VTK's config finds the
# packages of every module in the requested modules' dependency closure (public, private, optional and
# forward links: VTK-vtk-module-find-packages.cmake), and Debian's VTK has modules whose packages are found
# through C: mpi (FindMPI's C part, e.g. reached from the rendering modules), hdf5 and netcdf. Without C
# that find fails and VTK::mpi's link to MPI::MPI_C stops the consumer's generate step.
function(_cementsph_vtk_needs_c module outVar)
  set(stack ${module})
  set(seen)
  set(found FALSE)
  while(stack)
    list(POP_BACK stack current)
    string(REGEX REPLACE "^VTK::" "" current "${current}")
    if(current MATCHES "^(mpi|hdf5|netcdf)$")
      set(found TRUE)
      break()
    endif()
    if(current IN_LIST seen OR NOT TARGET VTK::${current})
      continue()
    endif()
    list(APPEND seen ${current})
    foreach(property depends private_depends optional_depends forward_link)
      get_property(next TARGET VTK::${current} PROPERTY INTERFACE_vtk_module_${property})
      list(APPEND stack ${next})
    endforeach()
  endwhile()
  set(${outVar} ${found} PARENT_SCOPE)
endfunction()

# A function, so that its loop variables (target, component, ...) do not leak into the directories after it.
function(_cementsph_install_package)
  set(_cementsph_components)
  set(_cementsph_component_table "")
  foreach(entry IN LISTS CEMENTSPH_EXPORTED_LIBRARIES CEMENTSPH_BUILD_FLAG_TARGETS)
    string(REPLACE ":" ";" pair "${entry}")
    list(GET pair 0 target)
    list(GET pair 1 component)
    set_target_properties(${target} PROPERTIES EXPORT_NAME ${component})
  endforeach()

  foreach(entry IN LISTS CEMENTSPH_EXPORTED_LIBRARIES)
    string(REPLACE ":" ";" pair "${entry}")
    list(GET pair 0 target)
    list(GET pair 1 component)
    list(APPEND _cementsph_components ${component})

    # Headers: the module's include/ folders (absolute, in the source tree) go to include/CementSPH/<component>,
    # and the installed target names only that folder, so a component exposes its own headers and those of
    # the components it links publicly, not every module's.
    get_target_property(includes ${target} INTERFACE_INCLUDE_DIRECTORIES)
    set(relocated)
    foreach(dir IN LISTS includes)
      string(FIND "${dir}/" "${PROJECT_SOURCE_DIR}/" inSource)
      string(FIND "${dir}/" "${PROJECT_BINARY_DIR}/" inBuild)
      if(inSource EQUAL 0 OR inBuild EQUAL 0)
        list(APPEND relocated "$<BUILD_INTERFACE:${dir}>")
        install(DIRECTORY ${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/CementSPH/${component})
      elseif(dir)
        list(APPEND relocated "${dir}")
      endif()
    endforeach()
    list(APPEND relocated "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/CementSPH/${component}>")
    set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${relocated}")

    install(TARGETS ${target} EXPORT CementSPH${component}Targets
      ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
      LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    install(EXPORT CementSPH${component}Targets NAMESPACE CementSPH:: DESTINATION ${CEMENTSPH_INSTALL_CMAKEDIR})

    # What the component links: other components (loaded first by the config) and third-party packages.
    get_target_property(links ${target} INTERFACE_LINK_LIBRARIES)
    set(dependsOn)
    set(packages)
    set(vtkModules)
    foreach(item IN LISTS links)
      if(item MATCHES "^\\$<BUILD_INTERFACE:" OR item STREQUAL "")
        continue() # not exported
      endif()
      if(item MATCHES "^\\$<LINK_ONLY:(.*)>$")
        set(item "${CMAKE_MATCH_1}")
      endif()
      if(item MATCHES "^CementSPH::(.*)$")
        set(linked "${CMAKE_MATCH_1}")
        if(NOT linked MATCHES "^(warnings|optimise)$")
          list(APPEND dependsOn ${linked})
        endif()
        continue()
      endif()
      if(item MATCHES "^CementSPH_" AND TARGET ${item}) # a module named by its target, not its alias
        get_target_property(linked ${item} EXPORT_NAME)
        if(NOT linked)
          string(REGEX REPLACE "^CementSPH_" "" linked "${item}") # not exported: named in the error below
        endif()
        list(APPEND dependsOn ${linked})
        continue()
      endif()
      if(IS_ABSOLUTE "${item}")
        continue() # a library file (libz, libOSMesa): linked by path, nothing to find
      endif()
      _cementsph_package_of("${item}" package)
      if(package STREQUAL "")
        message(WARNING "cmake/CementSPHInstall.cmake: ${target} links '${item}', and the installed package does not "
          "know which package defines it, so find_package(CementSPH COMPONENTS ${component}) will not find it: "
          "add it to _cementsph_package_of and to CementSPHConfig.cmake.in's package list.")
        continue()
      endif()
      list(APPEND packages ${package})
      if(package STREQUAL "VTK")
        string(REGEX REPLACE "^VTK::" "" module "${item}")
        list(APPEND vtkModules ${module})
      endif()
    endforeach()
    list(REMOVE_DUPLICATES dependsOn)
    list(REMOVE_DUPLICATES packages)
    list(REMOVE_DUPLICATES vtkModules)
    # C: ITK's config runs FindHDF5 (C test programs), MPI::MPI_C is found through C, and so are the
    # packages of some VTK modules.
    set(needsC FALSE)
    if("ITK" IN_LIST packages OR "MPI" IN_LIST packages)
      set(needsC TRUE)
    endif()
    foreach(module IN LISTS vtkModules)
      _cementsph_vtk_needs_c(${module} vtkNeedsC)
      if(vtkNeedsC)
        set(needsC TRUE)
      endif()
    endforeach()
    set(_cementsph_depends_${component} ${dependsOn})
    string(APPEND _cementsph_component_table
      "set(_CementSPH_${component}_COMPONENTS \"${dependsOn}\")\n"
      "set(_CementSPH_${component}_PACKAGES \"${packages}\")\n"
      "set(_CementSPH_${component}_VTK_MODULES \"${vtkModules}\")\n"
      "set(_CementSPH_${component}_NEEDS_C ${needsC})\n")
  endforeach()

  # The components in an order where each comes after every component it links: the config includes the
  # targets files in this order, since each checks that the targets it refers to exist.
  set(_cementsph_ordered)
  set(_cementsph_pending ${_cementsph_components})
  while(_cementsph_pending)
    set(progress FALSE)
    foreach(component IN LISTS _cementsph_pending)
      set(ready TRUE)
      foreach(dependency IN LISTS _cementsph_depends_${component})
        if(NOT dependency IN_LIST _cementsph_ordered)
          set(ready FALSE)
        endif()
      endforeach()
      if(ready)
        list(APPEND _cementsph_ordered ${component})
        list(REMOVE_ITEM _cementsph_pending ${component})
        set(progress TRUE)
      endif()
    endforeach()
    if(NOT progress)
      message(FATAL_ERROR "cmake/CementSPHInstall.cmake: the components ${_cementsph_pending} link each other in a "
        "cycle or link a CementSPH library that is not defined under Modules/ (not exported); move it there or break the cycle.")
    endif()
  endwhile()
  set(CEMENTSPH_CONFIG_COMPONENTS "${_cementsph_ordered}")
  set(CEMENTSPH_CONFIG_COMPONENT_TABLE "${_cementsph_component_table}")

  # The compile-flag targets every static library names as $<LINK_ONLY:...>.
  set(_cementsph_flag_targets)
  foreach(entry IN LISTS CEMENTSPH_BUILD_FLAG_TARGETS)
    string(REPLACE ":" ";" pair "${entry}")
    list(GET pair 0 target)
    list(APPEND _cementsph_flag_targets ${target})
  endforeach()
  install(TARGETS ${_cementsph_flag_targets} EXPORT CementSPHBuildFlagsTargets)
  install(EXPORT CementSPHBuildFlagsTargets NAMESPACE CementSPH:: DESTINATION ${CEMENTSPH_INSTALL_CMAKEDIR})

  # ITK's libraries come in as one list (${ITK_LIBRARIES}), so the config finds ITK with the project's
  # component list.
  set(CEMENTSPH_CONFIG_ITK_COMPONENTS ${CEMENTSPH_ITK_COMPONENTS})
  configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/CementSPHConfig.cmake.in
    ${CMAKE_CURRENT_BINARY_DIR}/CementSPHConfig.cmake
    INSTALL_DESTINATION ${CEMENTSPH_INSTALL_CMAKEDIR})
  write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/CementSPHConfigVersion.cmake
    VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
  install(FILES ${CMAKE_CURRENT_BINARY_DIR}/CementSPHConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/CementSPHConfigVersion.cmake
    DESTINATION ${CEMENTSPH_INSTALL_CMAKEDIR})
endfunction()
_cementsph_install_package()
