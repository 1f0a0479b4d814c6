# Every dependency is a Debian 12 package (scripts/setup installs them); nothing is
# downloaded at configure or build time.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)   # libeigen3-dev
find_package(TBB REQUIRED)                    # libtbb-dev (oneTBB 2021)
find_package(METIS REQUIRED)                  # libmetis-dev, see FindMETIS.cmake
find_package(hwy 1.0 REQUIRED)                # libhwy-dev (Highway: SIMD with runtime dispatch)
find_package(nlohmann_json 3.10 REQUIRED)      # nlohmann-json3-dev (scene files; used privately)
# Optional: the distributed solver's transport (tessera::distributed, distributed_solver.hpp).
find_package(MPI COMPONENTS CXX QUIET)         # libopenmpi-dev, openmpi-bin
option(TESSERA_MPI "Build the distributed solver over MPI (on when Open MPI is found)" ${MPI_CXX_FOUND})
if(TESSERA_MPI AND NOT MPI_CXX_FOUND)
  message(FATAL_ERROR "TESSERA_MPI is on but no MPI was found: install libopenmpi-dev and openmpi-bin (scripts/setup)")
endif()

# TESSERA_SIMD: how the batched kernels pick their instruction set.
#   dispatch (default)  compile for AVX-512, AVX2, SSE4 and a portable fallback, and pick the
#                       best the running CPU has on first use
#   native              compile only for the building machine (-march=native), no dispatch
#   scalar              compile only the portable fallback (Highway's EMU128)
set(TESSERA_SIMD "dispatch" CACHE STRING "SIMD target selection: dispatch, native or scalar")
set_property(CACHE TESSERA_SIMD PROPERTY STRINGS dispatch native scalar)
if(TESSERA_SIMD STREQUAL "dispatch")
  # AVX3_DL/ZEN4 add integer and bit instructions the kernels do not use, SSSE3 lacks the
  # rounding and blend instructions SSE4 has: leaving them out saves compile time only.
  set(TESSERA_SIMD_DEFINITIONS "HWY_DISABLED_TARGETS=(HWY_SSSE3|HWY_AVX3_DL)")
  set(TESSERA_SIMD_OPTIONS "")
elseif(TESSERA_SIMD STREQUAL "native")
  set(TESSERA_SIMD_DEFINITIONS "HWY_COMPILE_ONLY_STATIC=1")
  set(TESSERA_SIMD_OPTIONS "-march=native")
elseif(TESSERA_SIMD STREQUAL "scalar")
  set(TESSERA_SIMD_DEFINITIONS "HWY_COMPILE_ONLY_EMU128=1")
  set(TESSERA_SIMD_OPTIONS "")
else()
  message(FATAL_ERROR "TESSERA_SIMD must be dispatch, native or scalar (got '${TESSERA_SIMD}')")
endif()
