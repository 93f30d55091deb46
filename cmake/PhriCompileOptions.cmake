# Compile options for targets built from our own sources.
# Warnings are errors in our code; third-party headers come in as SYSTEM includes.

set(PHRI_MARCH_FLAG "")
if(PHRI_MARCH STREQUAL "auto")
  # x86-64-v3 (AVX2, FMA, BMI2) only when the compiler knows it and this machine runs it;
  # otherwise the portable default of the compiler.
  include(CheckCXXSourceRuns)
  set(CMAKE_REQUIRED_FLAGS "-march=x86-64-v3")
  check_cxx_source_runs("
    int main() {
      __builtin_cpu_init();
      return (__builtin_cpu_supports(\"avx2\") && __builtin_cpu_supports(\"fma\")
              && __builtin_cpu_supports(\"bmi2\")) ? 0 : 1;
    }" PHRI_HOST_RUNS_X86_64_V3)
  unset(CMAKE_REQUIRED_FLAGS)
  if(PHRI_HOST_RUNS_X86_64_V3)
    set(PHRI_MARCH_FLAG "-march=x86-64-v3")
  endif()
elseif(NOT PHRI_MARCH STREQUAL "none" AND NOT PHRI_MARCH STREQUAL "")
  set(PHRI_MARCH_FLAG "-march=${PHRI_MARCH}")
endif()

function(phri_target_options target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Werror
    $<$<CONFIG:Release,RelWithDebInfo>:-O3>)
  # GCC 12 reports false array-bounds errors inside Eigen's AVX code paths once inlined into our
  # functions (GCC bugs 106247 / 107852); the diagnostic is about Eigen's internals, not our code.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(${target} PRIVATE -Wno-array-bounds -Wno-stringop-overflow)
  endif()
  if(PHRI_MARCH_FLAG)
    target_compile_options(${target} PRIVATE ${PHRI_MARCH_FLAG})
  endif()
  # Shared library: calls between our own functions need not go through the PLT.
  target_compile_options(${target} PRIVATE -fno-semantic-interposition)
  if(PHRI_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
      -fno-sanitize-recover=undefined)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
