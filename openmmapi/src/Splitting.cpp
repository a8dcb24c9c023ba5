#include "internal/Splitting.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/** The table, built once (the Yoshida weights need a cube root). Indexed by RigidBodyOptions::Splitting. */
const SplittingScheme* buildSchemes() {
    // Omelyan, Mryglod and Folk, Phys. Rev. E 65, 056706 (2002): the velocity form of their optimized
    // two-stage scheme. lambda minimises the norm of the third-order error terms; in closed form
    // 1/2 - (2 sqrt(326) + 36)^(1/3)/12 + 1/(6 (2 sqrt(326) + 36)^(1/3)).
    const double lambda = 0.1931833275037836;
    // The triple jump (H. Yoshida, Phys. Lett. A 150, 262 (1990); also Forest and Ruth, Physica D 43,
    // 105 (1990) and Suzuki, Phys. Lett. A 146, 319 (1990)): three Verlet steps of w1, w0, w1 times dt
    // with 2 w1 + w0 = 1 and 2 w1^3 + w0^3 = 0, which cancels the dt^3 error of the symmetric step.
    // Adjacent half kicks merge, so it costs three force evaluations.
    const double w1 = 1.0/(2.0 - cbrt(2.0)), w0 = 1.0 - 2.0*w1;
    // Omelyan, Mryglod and Folk, Comput. Phys. Commun. 146, 188 (2002) (arXiv:cond-mat/0110585): the
    // velocity version of their optimized extended Forest-Ruth-like algorithm ("VEFRL"), fourth
    // order with five kicks, the first reusing the previous step's forces.
    const double xi = 0.1644986515575760, lambda4 = -0.02094333910398989, chi = 1.235692651138917;
    static const SplittingScheme schemes[NumSplittings] = {
        {"Verlet", 1, {0.5, 0.5}, {1.0}},
        {"Omelyan2", 2, {lambda, 1.0 - 2.0*lambda, lambda}, {0.5, 0.5}},
        {"Yoshida4", 3, {0.5*w1, 0.5*(w1 + w0), 0.5*(w0 + w1), 0.5*w1}, {w1, w0, w1}},
        {"Omelyan4", 4, {xi, chi, 1.0 - 2.0*(chi + xi), chi, xi},
                        {0.5*(1.0 - 2.0*lambda4), lambda4, lambda4, 0.5*(1.0 - 2.0*lambda4)}},
    };
    return schemes;
}

} // namespace

const SplittingScheme& splittingScheme(RigidBodyOptions::Splitting splitting) {
    static const SplittingScheme* schemes = buildSchemes();
    const int index = splitting;
    if (index < 0 || index >= NumSplittings) {
        string valid;
        for (int i = 0; i < NumSplittings; i++)
            valid += string(i == 0 ? "" : (i == NumSplittings - 1 ? " or " : ", ")) + "RigidBodyIntegrator." +
                     schemes[i].name + " (" + to_string(i) + ")";
        throw OpenMMException("RigidBodyIntegrator: unknown splitting " + to_string(index) + "; use " + valid);
    }
    return schemes[index];
}

} // namespace OpenMMRigid
