#include "internal/RigidBodyMolecules.h"
#include "openmm/OpenMMException.h"

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

RigidBodyMoleculesImpl::RigidBodyMoleculesImpl(const vector<vector<int> >& bodies) : owner(bodies) {
    for (const vector<int>& body : bodies)
        for (size_t i = 1; i < body.size(); i++)
            bonds.push_back({body[0], body[i]});
}

void RigidBodyMoleculesImpl::install(ContextImpl& context, const vector<vector<int> >& bodies, const string& className) {
    // The Context owns its ForceImpls and deletes them with itself. Its molecules are found on first
    // use, which comes later (the barostat's first move, the first wrapped State): unless a Force
    // already asked for them while it was initialized, which the check below catches.
    context.getForceImpls().push_back(new RigidBodyMoleculesImpl(bodies));
    const vector<vector<int> >& molecules = context.getMolecules();
    vector<int> moleculeOfParticle(context.getSystem().getNumParticles(), -1);
    for (size_t m = 0; m < molecules.size(); m++)
        for (int p : molecules[m])
            moleculeOfParticle[p] = m;
    for (size_t b = 0; b < bodies.size(); b++)
        for (int p : bodies[b])
            if (moleculeOfParticle[p] != moleculeOfParticle[bodies[b][0]])
                throw OpenMMException(className + ": body " + to_string(b) + " is not one molecule to this Context (a Force "
                        "found the molecules before the integrator could join the body's particles); bond its particles in the "
                        "System, for example with a HarmonicBondForce of zero force constant, so that barostats and periodic "
                        "wrapping keep it whole");
}

} // namespace OpenMMRigid
