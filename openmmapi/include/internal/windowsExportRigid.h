#ifndef OPENMMRIGID_WINDOWSEXPORTRIGID_H_
#define OPENMMRIGID_WINDOWSEXPORTRIGID_H_

/*
 * Symbol visibility for libOpenMMRigid, following OpenMM's windowsExport.h: exported on Windows
 * when building the library (OPENMM_RIGID_BUILDING_SHARED_LIBRARY), imported otherwise; default
 * visibility elsewhere, so that the classes stay visible when the rest is built hidden.
 */
#if defined(_MSC_VER)
    #if defined(OPENMM_RIGID_BUILDING_SHARED_LIBRARY)
        #define OPENMM_EXPORT_RIGID __declspec(dllexport)
    #else
        #define OPENMM_EXPORT_RIGID __declspec(dllimport)
    #endif
#else
    #define OPENMM_EXPORT_RIGID __attribute__((visibility("default")))
#endif

#endif // OPENMMRIGID_WINDOWSEXPORTRIGID_H_
