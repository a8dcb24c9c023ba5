// OpenMMRigid::Special's public functions as module functions, with their declarations and Doxygen
// (the docstrings, by SWIG's -doxygen) from numerics/Elliptic.h itself. The Python-facing versions,
// with m1 = 1 - m by default, are in openmmrigid/special.py.

%{
#include "numerics/Elliptic.h"
%}

// jacobiElliptic's three outputs come back as the tuple (sn, cn, dn).
%typemap(in, numinputs=0) (double& sn, double& cn, double& dn) (double snValue, double cnValue, double dnValue) {
    $1 = &snValue;
    $2 = &cnValue;
    $3 = &dnValue;
}
%typemap(argout) (double& sn, double& cn, double& dn) {
    Py_XDECREF($result);  // None, from the void return
    $result = Py_BuildValue("(ddd)", *$1, *$2, *$3);
    if ($result == NULL)
        SWIG_fail;
}
%typemap(doctype) void jacobiElliptic "tuple of float"

// Only the six public entry points: the header's helpers (detail::, the *FromJacobi forms, RC) stay C++.
%rename("$ignore", %$isfunction) "";
%rename("%s") OpenMMRigid::Special::jacobiElliptic;
%rename("%s") OpenMMRigid::Special::ellipticK;
%rename("%s") OpenMMRigid::Special::ellipticF;
%rename("%s") OpenMMRigid::Special::ellipticPi;
%rename("%s") OpenMMRigid::Special::carlsonRF;
%rename("%s") OpenMMRigid::Special::carlsonRJ;
%include "numerics/Elliptic.h"
%rename("%s", %$isfunction) "";
