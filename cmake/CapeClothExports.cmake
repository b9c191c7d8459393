# cape_export_api(TARGET BASE HEADER): the export macro <BASE>_API of a library, in the generated HEADER
# (e.g. cape/core/Export.h, under the build tree's include/ and installed beside the public headers). A
# shared build (BUILD_SHARED_LIBS) hides every symbol and exports only what the public headers mark with the
# macro; a static build compiles as before (the macro is empty).
include_guard(GLOBAL)
include(GenerateExportHeader)

function(cape_export_api target base header)
  set(file ${CMAKE_CURRENT_BINARY_DIR}/include/${header})
  generate_export_header(${target} BASE_NAME ${base} EXPORT_MACRO_NAME ${base}_API EXPORT_FILE_NAME ${file})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_BINARY_DIR}/include>)
  if(BUILD_SHARED_LIBS)
    set_target_properties(${target} PROPERTIES CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
  endif()
  get_filename_component(dir ${header} DIRECTORY)
  install(FILES ${file} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/${dir})
endfunction()
