// OpenMMRigid::FreeRotor through its buffer-level adaptor; openmmrigid/freerotor.py builds the
// user-facing class on top of it.

%{
#include "FreeRotorAdaptor.h"
%}

%apply (const double* IN_ARRAY, std::size_t IN_LENGTH) {
    (const double* moments, std::size_t momentsLength),
    (const double* omega, std::size_t omegaLength),
    (const double* attitude, std::size_t attitudeLength),
    (const double* times, std::size_t numTimes)
};
%apply (double* OUT_ARRAY, std::size_t OUT_LENGTH) {
    (double* omegaOut, std::size_t omegaLength),
    (double* attitudeOut, std::size_t attitudeLength),
    (double* out, std::size_t length)
};

// The representations, as openmmrigid/freerotor.py maps its strings onto them.
%constant int FreeRotorAutomatic = OpenMMRigid::FreeRotor::Automatic;
%constant int FreeRotorThetaSeries = OpenMMRigid::FreeRotor::ThetaSeries;
%constant int FreeRotorEllipticIntegral = OpenMMRigid::FreeRotor::EllipticIntegral;

%include "FreeRotorAdaptor.h"
