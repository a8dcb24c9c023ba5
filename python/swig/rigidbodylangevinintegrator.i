// OpenMMRigid::RigidBodyLangevinIntegrator as a subclass of openmm.Integrator (through
// RigidBodyIntegratorBase, wrapped in rigidbodyintegrator.i with the typemaps both classes use). Its
// docstrings are the header's Doxygen (SWIG's -doxygen); units follow OpenMM's
// LangevinMiddleIntegrator (the temperature, friction and step size may be openmm.unit Quantities;
// getTemperature and getFriction return Quantities), added by openmmrigid/_pythonapi.py.

%include "RigidBodyLangevinIntegrator.h"
