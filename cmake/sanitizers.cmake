# SLUICE_SANITIZE=address,undefined or thread: applied to every target.
if(SLUICE_SANITIZE)
  # -g1: line tables, all a sanitizer report needs (file:line in every frame);
  # full debug info only adds compile and link time to these builds.
  add_compile_options(-fsanitize=${SLUICE_SANITIZE} -fno-omit-frame-pointer -g1)
  add_link_options(-fsanitize=${SLUICE_SANITIZE})
  if(SLUICE_SANITIZE MATCHES "undefined")
    add_compile_options(-fno-sanitize-recover=undefined)
  endif()
endif()

# Coverage instrumentation for the libFuzzer targets (clang only).
if(SLUICE_FUZZ)
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()
