// OpenMMRigid::Special as module functions. The Python-facing versions, with m1 = 1 - m by default,
// are in openmmrigid/special.py. Declarations copied from numerics/Elliptic.h (same signatures).

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

namespace OpenMMRigid {
namespace Special {

void jacobiElliptic(double u, double m, double m1, double& sn, double& cn, double& dn);
double ellipticK(double m, double m1);
double ellipticF(double x, double m, double m1);
double ellipticPi(double n, double x, double m, double m1);
double carlsonRF(double x, double y, double z);
double carlsonRJ(double x, double y, double z, double p);

} // namespace Special
} // namespace OpenMMRigid
