# Fails if the kernel archive references the allocator, exception machinery,
# RTTI or iostreams. Run as: cmake -DNM=<nm> -DARCHIVE=<lib> -P this-file
# With -DWHOLE_PROGRAM=ON, ARCHIVE is a linked executable (the firmware ELF)
# and every symbol in it is checked, defined or not: none of these may be
# linked in at all.
if(WHOLE_PROGRAM)
  execute_process(COMMAND ${NM} ${ARCHIVE} OUTPUT_VARIABLE undefined RESULT_VARIABLE rc)
else()
  execute_process(COMMAND ${NM} -u ${ARCHIVE} OUTPUT_VARIABLE undefined RESULT_VARIABLE rc)
endif()
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${NM} failed on ${ARCHIVE}")
endif()
set(forbidden
  "malloc" "calloc" "realloc" "free" "aligned_alloc" "posix_memalign"
  "_Znw" "_Zna" "_Zdl" "_Zda"                       # operator new/delete
  "__cxa_throw" "__cxa_allocate_exception" "__cxa_begin_catch" "__gxx_personality"
  "_ZTI" "__dynamic_cast"                            # RTTI
  "_ZSt4cout" "_ZSt4cerr" "_ZNSo" "_ZNSi" "printf" "puts"  # iostreams, stdio
  "__cxa_guard_acquire"                              # thread-safe statics
  "sinf" "cosf" "sin" "cos" "lroundf"                # libm: differs across targets
)
string(REPLACE "\n" ";" lines "${undefined}")
set(found "")
foreach(line IN LISTS lines)
  string(REGEX REPLACE "^.* [A-Za-z] " "" sym "${line}")
  string(STRIP "${sym}" sym)
  foreach(bad IN LISTS forbidden)
    if(sym STREQUAL bad OR (sym MATCHES "^${bad}" AND bad MATCHES "^_Z|^__"))
      list(APPEND found "${sym}")
    endif()
  endforeach()
endforeach()
if(found)
  list(REMOVE_DUPLICATES found)
  message(FATAL_ERROR "kernel references forbidden symbols: ${found}")
endif()
message(STATUS "${ARCHIVE}: no allocator, exception, RTTI, iostream or libm symbols")
