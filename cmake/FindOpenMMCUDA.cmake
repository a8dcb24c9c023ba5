#[=======================================================================[.rst:
FindOpenMMCUDA
--------------

Finds what a CUDA plugin of OpenMM needs to build with a plain C++ compiler: the openmm-cuda wheel's
``libOpenMMCUDA.so`` and the CUDA driver API headers (``cuda.h``, ``builtin_types.h``,
``vector_functions.h``) that OpenMM's CUDA headers include. No nvcc and no CUDA library: OpenMM
compiles the kernels at run time with NVRTC, and libOpenMMCUDA.so brings the driver, NVRTC and cuFFT.

Call after ``find_package(OpenMM)``. ``pip install openmm-cuda-13==8.6.1`` puts both into the
interpreter's site-packages (``OpenMM.libs/lib/plugins`` and ``nvidia/cu13/include``); the headers
are also taken from a CUDA toolkit (``find_package(CUDAToolkit)``) when pip's are not there.

Input: the cache variables ``OPENMM_CUDA_LIBRARY`` and ``OPENMM_CUDA_INCLUDE_DIR`` (both found when unset).

Results: ``OpenMMCUDA_FOUND``; the imported target ``OpenMM::CUDA`` (libOpenMMCUDA.so with the
CUDA headers as its include directory); ``OPENMM_CUDA_LIBRARY``; ``OPENMM_CUDA_INCLUDE_DIR``.
#]=======================================================================]

include(FindPackageHandleStandardArgs)

# site-packages: OPENMM_DIR is the wheel's site-packages/OpenMM.libs.
get_filename_component(_openmmCudaSitePackages "${OPENMM_DIR}/.." ABSOLUTE)

find_library(OPENMM_CUDA_LIBRARY NAMES OpenMMCUDA
             HINTS "${OPENMM_DIR}/lib/plugins" NO_DEFAULT_PATH
             DOC "libOpenMMCUDA.so of the openmm-cuda-13 wheel (pip install openmm-cuda-13==8.6.1)")

find_path(OPENMM_CUDA_INCLUDE_DIR NAMES cuda.h
          HINTS "${_openmmCudaSitePackages}/nvidia/cu13/include" NO_DEFAULT_PATH
          DOC "Folder with the CUDA driver API headers (cuda.h)")
if(NOT OPENMM_CUDA_INCLUDE_DIR)
    find_package(CUDAToolkit QUIET)
    if(CUDAToolkit_FOUND)
        find_path(OPENMM_CUDA_INCLUDE_DIR NAMES cuda.h
                  HINTS ${CUDAToolkit_INCLUDE_DIRS} NO_DEFAULT_PATH)
    endif()
endif()

find_package_handle_standard_args(OpenMMCUDA
    REQUIRED_VARS OPENMM_CUDA_LIBRARY OPENMM_CUDA_INCLUDE_DIR
    REASON_FAILURE_MESSAGE "pip install openmm-cuda-13==8.6.1 into the environment of ${OPENMM_DIR} \
(it brings libOpenMMCUDA.so and cuda.h), or set OPENMM_CUDA_LIBRARY and OPENMM_CUDA_INCLUDE_DIR")

if(OpenMMCUDA_FOUND AND NOT TARGET OpenMM::CUDA)
    add_library(OpenMM::CUDA SHARED IMPORTED)
    set_target_properties(OpenMM::CUDA PROPERTIES
        IMPORTED_LOCATION "${OPENMM_CUDA_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${OPENMM_CUDA_INCLUDE_DIR}")
endif()
