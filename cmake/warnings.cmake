# Warnings for the project's own targets (not for third-party headers).
# SLUICE_WERROR (CI's Release build) turns them into errors.
option(SLUICE_WERROR "Treat the project's warnings as errors" OFF)
function(sluice_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion>
    $<$<AND:$<BOOL:${SLUICE_WERROR}>,$<CXX_COMPILER_ID:GNU,Clang>>:-Werror>)
endfunction()

# GCC 12 reports -Wrestrict for `"literal" + std::string` once inlined
# (GCC PR 105329: an overlap of 2^63 bytes at offset -3, a false positive);
# the files where it occurs say so here instead of rewriting their messages.
function(sluice_gcc12_string_concat_false_positive)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    set_source_files_properties(${ARGN} DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR} PROPERTIES COMPILE_OPTIONS -Wno-restrict)
  endif()
endfunction()
