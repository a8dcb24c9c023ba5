#include "internal/RigidBodySystem.h"
#include "numerics/SymmetricEigen.h"
#include "openmm/CMMotionRemover.h"
#include "openmm/CustomNonbondedForce.h"
#include "openmm/NonbondedForce.h"
#include "openmm/OpenMMException.h"
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

const char* RigidBody::kindName(Kind kind) {
    static const char* names[] = {"point", "linear", "spherical", "symmetric", "asymmetric"};
    return names[kind];
}

void RigidBody::setShape(const vector<Vector3>& centred) {
    Matrix3 axes;
    principalAxes(centred, masses, moments, axes);
    bodyCoordinates.resize(centred.size());
    for (size_t i = 0; i < centred.size(); i++)
        bodyCoordinates[i] = multiplyTransposed(axes, centred[i]);
    // The smallest moment of a linear molecule computed from coordinates is rounding noise, not zero:
    // snap it, so that the body gets the exact linear-rotor flow with two rotational degrees of freedom.
    const double largest = moments[2];
    if (particles.size() == 1 || largest == 0.0) {
        kind = Point;
        moments = {0.0, 0.0, 0.0};
        for (Vector3& b : bodyCoordinates)
            b = {0.0, 0.0, 0.0};
    }
    else if (moments[0] <= 1e-10*largest) {
        kind = Linear;
        double perpendicular = 0.0;
        for (size_t i = 0; i < centred.size(); i++) {
            bodyCoordinates[i][1] = bodyCoordinates[i][2] = 0.0;
            perpendicular += masses[i]*bodyCoordinates[i][0]*bodyCoordinates[i][0];
        }
        moments = {0.0, perpendicular, perpendicular};
    }
    else {
        // The moments the dynamics uses are those of the stored coordinates themselves (the diagonal of
        // their inertia tensor), so that the shape and the rotor agree to rounding.
        for (int k = 0; k < 3; k++) {
            double moment = 0.0;
            for (size_t i = 0; i < bodyCoordinates.size(); i++) {
                const Vector3& b = bodyCoordinates[i];
                moment += masses[i]*(dot(b, b) - b[k]*b[k]);
            }
            moments[k] = moment;
        }
        // The reported kind treats moments within 1e-10 relative as equal: coordinates a few nm from the
        // origin carry rounding of about 1e-14 relative into the moments of a truly symmetric shape.
        // The dynamics is unaffected: FreeRotor takes the exact formula for the moments as they are.
        const double tolerance = 1e-10*largest;
        bool equal01 = moments[1] - moments[0] <= tolerance, equal12 = moments[2] - moments[1] <= tolerance;
        kind = (equal01 && equal12 ? Spherical : (equal01 || equal12 ? Symmetric : Asymmetric));
    }
    shapeKnown = true;
}

RigidBodySystem::RigidBodySystem(const System& system, const vector<vector<int> >& explicitBodies, bool useExplicit,
                                 const string& className) : className(className) {
    const int numParticles = system.getNumParticles();
    masses.resize(numParticles);
    for (int i = 0; i < numParticles; i++)
        masses[i] = system.getParticleMass(i);
    bodyOfParticle.assign(numParticles, -1);
    if (useExplicit) {
        for (size_t b = 0; b < explicitBodies.size(); b++) {
            RigidBody body;
            body.particles = explicitBodies[b];
            if (body.particles.empty())
                throw OpenMMException(className + ": body " + to_string(b) + " has no particles");
            for (int p : body.particles) {
                if (p < 0 || p >= numParticles)
                    throw OpenMMException(className + ": body " + to_string(b) + " lists particle " + to_string(p) +
                            ", but the System has particles 0 to " + to_string(numParticles - 1));
                if (bodyOfParticle[p] == (int) b)
                    throw OpenMMException(className + ": body " + to_string(b) + " lists particle " + to_string(p) + " twice");
                if (bodyOfParticle[p] != -1)
                    throw OpenMMException(className + ": particle " + to_string(p) + " is in body " +
                            to_string(bodyOfParticle[p]) + " and in body " + to_string(b) + "; a particle may belong to one body only");
                bodyOfParticle[p] = b;
            }
            bodies.push_back(body);
        }
    }
    else
        findConstraintBodies(system);
    for (size_t b = 0; b < bodies.size(); b++)
        checkBody(system, b);

    // Constraints inside a body are implied by its rigidity; those among free particles stay.
    internalConstraints.resize(bodies.size());
    vector<pair<int, int> > kept;
    vector<double> keptDistances;
    for (int c = 0; c < system.getNumConstraints(); c++) {
        int i, j;
        double distance;
        system.getConstraintParameters(c, i, j, distance);
        int bi = bodyOfParticle[i], bj = bodyOfParticle[j];
        if (bi == -1 && bj == -1) {
            kept.push_back({i, j});
            keptDistances.push_back(distance);
        }
        else if (bi == bj) {
            const vector<int>& members = bodies[bi].particles;
            int first = find(members.begin(), members.end(), i) - members.begin();
            int second = find(members.begin(), members.end(), j) - members.begin();
            internalConstraints[bi].push_back({c, first, second, distance});
        }
        else {
            auto describe = [](int particle, int body) {
                return "particle " + to_string(particle) + (body == -1 ? " (free)" : " (body " + to_string(body) + ")");
            };
            throw OpenMMException(className + ": constraint " + to_string(c) + " joins " + describe(i, bi) + " and " +
                    describe(j, bj) + "; a constraint may not connect a rigid body to anything outside it");
        }
    }
    if (!kept.empty()) {
        freeConstraints.reset(new System());
        for (int i = 0; i < numParticles; i++)
            freeConstraints->addParticle(masses[i]);
        for (size_t c = 0; c < kept.size(); c++)
            freeConstraints->addConstraint(kept[c].first, kept[c].second, keptDistances[c]);
    }
    numFreeConstraints = kept.size();
    for (int i = 0; i < numParticles; i++)
        if (bodyOfParticle[i] == -1 && masses[i] != 0.0)
            freeParticles.push_back(i);
    double cutoff = 0.0;
    for (int f = 0; f < system.getNumForces(); f++) {
        const Force& force = system.getForce(f);
        if (dynamic_cast<const CMMotionRemover*>(&force) != NULL)
            removesCenterOfMassMotion = true;
        else if (const NonbondedForce* nonbonded = dynamic_cast<const NonbondedForce*>(&force)) {
            if (nonbonded->getNonbondedMethod() != NonbondedForce::NoCutoff)
                cutoff = max(cutoff, nonbonded->getCutoffDistance());
        }
        else if (const CustomNonbondedForce* custom = dynamic_cast<const CustomNonbondedForce*>(&force)) {
            if (custom->getNonbondedMethod() != CustomNonbondedForce::NoCutoff)
                cutoff = max(cutoff, custom->getCutoffDistance());
        }
    }
    largestCutoff = (cutoff > 0.0 ? cutoff : numeric_limits<double>::infinity());
}

void RigidBodySystem::findConstraintBodies(const System& system) {
    // Connected components of the constraint graph (union-find).
    const int numParticles = system.getNumParticles();
    vector<int> parent(numParticles);
    iota(parent.begin(), parent.end(), 0);
    function<int(int)> root = [&](int i) { return parent[i] == i ? i : parent[i] = root(parent[i]); };
    for (int c = 0; c < system.getNumConstraints(); c++) {
        int i, j;
        double distance;
        system.getConstraintParameters(c, i, j, distance);
        parent[root(i)] = root(j);
    }
    // Each cluster's members and constraints, gathered in one pass over each list.
    map<int, vector<int> > clusters, clusterConstraints;
    for (int c = 0; c < system.getNumConstraints(); c++) {
        int i, j;
        double distance;
        system.getConstraintParameters(c, i, j, distance);
        clusterConstraints[root(i)].push_back(c);
    }
    for (int i = 0; i < numParticles; i++)
        if (clusterConstraints.count(root(i)))
            clusters[root(i)].push_back(i);
    for (auto& entry : clusters) {
        const vector<int>& members = entry.second;
        const vector<int>& constraints = clusterConstraints[entry.first];
        int n = members.size();
        // A cluster of n >= 3 particles is rigid when its constraints fix all 3n - 6 internal degrees
        // of freedom; a chain such as X-H bonds in a flexible solute has fewer and stays free.
        if (n < 3 || (int) constraints.size() < 3*n - 6)
            continue;
        RigidBody body;
        body.particles = members;
        int b = bodies.size();
        for (int p : members)
            bodyOfParticle[p] = b;
        // When every pair is constrained the distances fix the shape: keep them for checkBody().
        map<pair<int, int>, double> distances;
        for (int c : constraints) {
            int i, j;
            double distance;
            system.getConstraintParameters(c, i, j, distance);
            distances[{min(i, j), max(i, j)}] = distance;
        }
        if ((int) distances.size() == n*(n - 1)/2) {
            body.pairDistances.resize(n*n, 0.0);
            for (int i = 0; i < n; i++)
                for (int j = i + 1; j < n; j++)
                    body.pairDistances[i*n + j] = body.pairDistances[j*n + i] = distances[{members[i], members[j]}];
        }
        bodies.push_back(body);
    }
}

void RigidBodySystem::checkBody(const System& system, int index) {
    RigidBody& body = bodies[index];
    for (int p : body.particles) {
        if (system.isVirtualSite(p))
            throw OpenMMException(className + ": particle " + to_string(p) + " of body " + to_string(index) +
                    " is a virtual site; virtual sites follow their parent particles and cannot be body members");
        if (masses[p] == 0.0)
            throw OpenMMException(className + ": particle " + to_string(p) + " of body " + to_string(index) +
                    " has zero mass; every body member must be massive");
        body.masses.push_back(masses[p]);
        body.mass += masses[p];
    }
    if (body.pairDistances.empty())
        return;
    // Classical multidimensional scaling: the centred Gram matrix -1/2 J D^2 J of the constraint
    // distances has rank <= 3, and its leading eigenvectors scaled by sqrt(eigenvalue) are coordinates
    // reproducing every distance (Torgerson, Psychometrika 17, 401 (1952)).
    const int n = body.particles.size();
    vector<double> gram(n*n), rowMean(n, 0.0);
    double mean = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double d2 = body.pairDistances[i*n + j]*body.pairDistances[i*n + j];
            rowMean[i] += d2/n;
            mean += d2/(n*n);
        }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double d2 = body.pairDistances[i*n + j]*body.pairDistances[i*n + j];
            gram[i*n + j] = -0.5*(d2 - rowMean[i] - rowMean[j] + mean);
        }
    vector<double> values, vectors;
    symmetricEigen(gram, n, values, vectors);
    vector<Vector3> coordinates(n, Vector3{0.0, 0.0, 0.0});
    for (int k = 0; k < min(3, n); k++) {
        int column = n - 1 - k;
        double scale = sqrt(max(values[column], 0.0));
        for (int i = 0; i < n; i++)
            coordinates[i][k] = vectors[i*n + column]*scale;
    }
    Vector3 center = {0.0, 0.0, 0.0};
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            center[k] += body.masses[i]*coordinates[i][k]/body.mass;
    for (Vector3& x : coordinates)
        for (int k = 0; k < 3; k++)
            x[k] -= center[k];
    body.setShape(coordinates);
    // Distances do not tell a three-dimensional shape from its mirror image; the first fit to
    // positions does. Planar and linear shapes are their own mirror images up to a rotation.
    double planarity = fabs(body.moments[2] - body.moments[1] - body.moments[0]);
    body.handednessOpen = (body.kind != RigidBody::Point && body.kind != RigidBody::Linear &&
                           planarity > 1e-10*body.moments[2]);
}

int RigidBodySystem::getNumDegreesOfFreedom() const {
    int dof = 3*freeParticles.size() - numFreeConstraints;
    for (const RigidBody& body : bodies)
        dof += 3 + (body.kind == RigidBody::Point ? 0 : body.kind == RigidBody::Linear ? 2 : 3);
    if (removesCenterOfMassMotion)
        dof -= 3;
    return dof;
}

} // namespace OpenMMRigid
