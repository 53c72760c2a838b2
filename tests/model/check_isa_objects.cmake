# ctest model/GramKernels.ExportOnlyTheirAccessor: the AVX2 / AVX-512 Gram
# kernels are compiled with -mavx2 / -mavx512f, so they must not define any
# symbol the linker could pick for the rest of the program (an inline function
# or template instantiated there is a weak symbol; if the linker keeps that
# copy, baseline code runs AVX instructions — the ODR trap that crashed the
# PCA once). Every global symbol they define must be their MicroKernel accessor,
# except type information of function types (_ZTIF..., _ZTSF...: read-only
# data, no instructions) that UBSan's -fsanitize=function emits for the
# function pointers the kernels use.
# Arguments: -DNM=<nm> -DOBJECTS=<;-list of samp_model's object files>.
set(checked 0)
foreach(object IN LISTS OBJECTS)
  if(NOT object MATCHES "gram_avx")
    continue()
  endif()
  math(EXPR checked "${checked} + 1")
  execute_process(COMMAND "${NM}" --defined-only "${object}"
                  OUTPUT_VARIABLE symbols RESULT_VARIABLE status)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${NM} failed on ${object}")
  endif()
  string(REPLACE "\n" ";" lines "${symbols}")
  foreach(line IN LISTS lines)
    # "<address> <type> <name>": upper-case types and u/v/w are visible to the linker.
    # Names stay mangled (the accessor is samp::gram_internal::*MicroKernel()).
    if(line MATCHES "^[0-9a-fA-F]* ([A-Zuvw]) (.*)$")
      set(type "${CMAKE_MATCH_1}")
      set(name "${CMAKE_MATCH_2}")
      if(NOT name MATCHES "^_ZN4samp13gram_internal[0-9]+[A-Za-z0-9]*MicroKernelEv$" AND
         NOT (type MATCHES "^[VR]$" AND name MATCHES "^_ZT[IS]F"))
        message(FATAL_ERROR "${object} defines the global symbol '${name}' (type ${type}); "
                            "the AVX kernels must keep everything but their accessor "
                            "internal")
      endif()
    endif()
  endforeach()
endforeach()
message(STATUS "checked ${checked} kernel object(s)")
