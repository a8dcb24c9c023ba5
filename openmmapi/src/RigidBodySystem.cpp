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

StepGeometry::StepGeometry() : displacementLimit(numeric_limits<double>::infinity()) {
}

void RigidBodySystem::setShape(int b, const vector<Vector3>& centred) {
    const int n = getBodySize(b);
    const int* members = getBodyParticles(b);
    Vector3* coordinates = &bodyCoordinates[bodyStart[b]];
    vector<double> bodyMasses(n);
    for (int i = 0; i < n; i++)
        bodyMasses[i] = masses[members[i]];
    Matrix3 axes;
    Vector3 moment;
    principalAxes(centred, bodyMasses, moment, axes);
    for (int i = 0; i < n; i++)
        coordinates[i] = multiplyTransposed(axes, centred[i]);
    // The moments the dynamics uses are those of the stored coordinates themselves (the diagonal of
    // their inertia tensor), so that the shape and the rotor agree to rounding; the one classification
    // of the numerics core (rigidClassifyMoments) then gives the kind and makes the moments it finds
    // equal (or zero) exactly so.
    RigidShape& shape = shapes[b];
    if (n == 1 || moment[2] == 0.0) {
        for (int i = 0; i < n; i++)
            coordinates[i] = {0.0, 0.0, 0.0};
        moment = {0.0, 0.0, 0.0};
    }
    else {
        // A molecule read from a file, a template or a minimizer is never exactly linear: one whose
        // particles all lie near the axis of least moment (within LinearTolerance, and within 1 % of
        // its reach along the axis) is put on that axis exactly, so that it is a linear body rather
        // than an asymmetric top with a tiny moment that spins too fast for any step.
        double offAxis = 0.0, alongAxis = 0.0;
        for (int i = 0; i < n; i++) {
            offAxis = max(offAxis, sqrt(coordinates[i][1]*coordinates[i][1] + coordinates[i][2]*coordinates[i][2]));
            alongAxis = max(alongAxis, fabs(coordinates[i][0]));
        }
        if (offAxis <= LinearTolerance && offAxis <= 0.01*alongAxis)
            for (int i = 0; i < n; i++)
                coordinates[i][1] = coordinates[i][2] = 0.0;
        for (int k = 0; k < 3; k++) {
            double sum = 0.0;
            for (int i = 0; i < n; i++)
                sum += bodyMasses[i]*(dot(coordinates[i], coordinates[i]) - coordinates[i][k]*coordinates[i][k]);
            moment[k] = sum;
        }
    }
    if (rigidClassifyMoments(moment.data(), &massMoments[b]) != RigidStatusOk)
        throw OpenMMException(className + ": body " + to_string(b) + " has principal moments " + to_string(moment[0]) + ", " +
                to_string(moment[1]) + ", " + to_string(moment[2]) + ", which no rigid body has");
    // Raised moments: every nonzero moment below the minimum is raised to it (a zero moment, the axis of
    // a line, carries no motion and stays zero). The configurational distribution does not depend on
    // the moments, only the dynamics does; the particles keep moving with v_i = V + omega x r_i.
    shape = massMoments[b];
    double raised[3];
    bool raises = false;
    for (int k = 0; k < 3; k++) {
        raised[k] = (shape.moments[k] > 0.0 ? max(shape.moments[k], minimumMoment) : 0.0);
        raises = raises || raised[k] != shape.moments[k];
    }
    if (raises && rigidClassifyMoments(raised, &shape) != RigidStatusOk)
        throw OpenMMException(className + ": internal error: body " + to_string(b) + "'s raised moments cannot be classified");
    for (int k = 0; k < 3; k++)
        inertiaScale[3*b + k] = (massMoments[b].moments[k] > 0.0 ? shape.moments[k]/massMoments[b].moments[k] : 1.0);
    longestLink[b] = spanningTree(b, [&](int i, int j) {
        double sum = 0.0;
        for (int k = 0; k < 3; k++)
            sum += (coordinates[i][k] - coordinates[j][k])*(coordinates[i][k] - coordinates[j][k]);
        return sqrt(sum);
    }, &assemblyOrder[bodyStart[b]], &assemblyNeighbour[bodyStart[b]]);
    shapeKnown[b] = 1;
}

void RigidBodySystem::settleHandedness(int b, bool mirror) {
    if (mirror)
        for (int i = bodyStart[b]; i < bodyStart[b + 1]; i++)
            bodyCoordinates[i][2] = -bodyCoordinates[i][2];
    handednessOpen[b] = 0;
}

bool RigidBodySystem::hasRaisedMoments() const {
    for (int b = 0; b < getNumBodies(); b++)
        if (rigidMomentsRaised(getInertiaScale(b)))
            return true;
    return false;
}

bool RigidBodySystem::allShapesKnown() const {
    for (char known : shapeKnown)
        if (!known)
            return false;
    return true;
}

void RigidBodySystem::requireFinite(const Vec3& v, const char* quantity, int particle, int body) const {
    if (!(isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2])))
        throw OpenMMException(className + ": particle " + to_string(particle) + " of body " + to_string(body) +
                " has a non-finite " + quantity);
}

namespace {

/**
 * sum_i m_i x_i / M: the one formula of a centre of mass, for either way of finding x_i. (Each term
 * is divided by M, as the fits always did, so that trajectories stay bit for bit.)
 */
template <class Value>
Vector3 massWeightedMean(const vector<double>& masses, const int* members, int n, double totalMass, Value value) {
    Vector3 mean = {0.0, 0.0, 0.0};
    for (int i = 0; i < n; i++) {
        const Vec3& x = value(i);
        const double m = masses[members[i]];
        for (int k = 0; k < 3; k++)
            mean[k] += m*x[k]/totalMass;
    }
    return mean;
}

} // namespace

Vector3 RigidBodySystem::centreOfMass(int b, const Vec3* values) const {
    return massWeightedMean(masses, getBodyParticles(b), getBodySize(b), bodyMass[b], [&](int i) -> const Vec3& { return values[i]; });
}

Vector3 RigidBodySystem::centreOfMass(int b, const Vec3* values, vector<Vector3>& offsets) const {
    const Vector3 center = centreOfMass(b, values);
    const int n = getBodySize(b);
    offsets.resize(n);
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            offsets[i][k] = values[i][k] - center[k];
    return center;
}

Vector3 RigidBodySystem::centreOfMass(int b, const vector<Vec3>& values) const {
    const int* members = getBodyParticles(b);
    return massWeightedMean(masses, members, getBodySize(b), bodyMass[b], [&](int i) -> const Vec3& { return values[members[i]]; });
}

namespace {

/**
 * r moved by whole box vectors to its image nearest anchor. The box is in OpenMM's reduced form: c,
 * then b, then a removes each component in turn. r comes back bit for bit if it is already nearest.
 */
Vec3 imageNearest(Vec3 r, const Vec3& anchor, const StepGeometry& geometry) {
    for (int k = 2; k >= 0; k--) {
        double shift = round((r[k] - anchor[k])/geometry.box[k][k]);
        if (shift != 0.0)
            r -= geometry.box[k]*shift;
    }
    return r;
}

} // namespace

double RigidBodySystem::spanningTree(int b, const function<double(int, int)>& distance, int* order, int* neighbour) const {
    // Prim's algorithm: each round places the unplaced particle with the shortest link to a placed
    // one. A link that is not finite is never the shortest; such a particle hangs on the first one.
    const int n = getBodySize(b);
    vector<double> shortest(n, numeric_limits<double>::infinity());
    vector<char> placed(n, 0);
    for (int i = 0; i < n; i++)
        neighbour[i] = 0;
    neighbour[0] = -1;
    order[0] = 0;
    placed[0] = 1;
    double longest = 0.0;
    for (int k = 1, last = 0; k < n; k++) {
        int next = -1;
        for (int j = 0; j < n; j++) {
            if (placed[j])
                continue;
            const double d = distance(last, j);
            if (d < shortest[j]) {
                shortest[j] = d;
                neighbour[j] = last;
            }
            if (next < 0 || shortest[j] < shortest[next])
                next = j;
        }
        placed[next] = 1;
        order[k] = next;
        if (isfinite(shortest[next]))
            longest = max(longest, shortest[next]);
        last = next;
    }
    return longest;
}

void RigidBodySystem::assemble(int b, const vector<Vec3>& positions, const StepGeometry& geometry, Vec3* whole) const {
    const int n = getBodySize(b);
    const int* members = getBodyParticles(b);
    if (!geometry.periodic || n == 1) {
        for (int i = 0; i < n; i++)
            whole[i] = positions[members[i]];
        return;
    }
    const int* order;
    const int* neighbour;
    vector<int> ownOrder, ownNeighbour;
    if (shapeKnown[b]) {
        // The body's own links: the same tree whatever the positions, checked against this box.
        order = &assemblyOrder[bodyStart[b]];
        neighbour = &assemblyNeighbour[bodyStart[b]];
        const double halfWidth = 0.5*min(geometry.box[0][0], min(geometry.box[1][1], geometry.box[2][2]));
        if (longestLink[b] >= halfWidth) {
            ostringstream message;
            message << className << ": body " << b << " cannot be assembled from periodic images unambiguously: some of its "
                    "particles are joined to the rest by no chain of links shorter than " << longestLink[b] << " nm, and half "
                    "the periodic box's smallest width is " << halfWidth << " nm; use a larger box";
            throw OpenMMException(message.str());
        }
    }
    else {
        // No shape yet: the links are the minimum-image distances in these positions.
        ownOrder.resize(n);
        ownNeighbour.resize(n);
        spanningTree(b, [&](int i, int j) {
            const Vec3& anchor = positions[members[i]];
            const Vec3 d = imageNearest(positions[members[j]], anchor, geometry) - anchor;
            return sqrt(d.dot(d));
        }, ownOrder.data(), ownNeighbour.data());
        order = ownOrder.data();
        neighbour = ownNeighbour.data();
    }
    whole[0] = positions[members[0]];
    for (int k = 1; k < n; k++) {
        const int i = order[k];
        whole[i] = imageNearest(positions[members[i]], whole[neighbour[i]], geometry);
    }
}

void RigidBodySystem::captureShapes(const vector<Vec3>& positions, const StepGeometry& geometry, bool strict,
                                    double constraintTolerance) {
    for (int b = 0; b < getNumBodies(); b++)
        if (!shapeKnown[b])
            shapeBody(b, positions, geometry, strict, constraintTolerance);
}

bool RigidBodySystem::canShape(int b, const vector<Vec3>& positions, const StepGeometry& geometry, bool strict) const {
    const int n = getBodySize(b);
    const int* members = getBodyParticles(b);
    vector<Vec3> whole(n);
    assemble(b, positions, geometry, whole.data());
    bool finite = true, spread = (n == 1);
    for (int i = 0; i < n; i++) {
        finite = finite && isfinite(whole[i][0]) && isfinite(whole[i][1]) && isfinite(whole[i][2]);
        spread = spread || whole[i] != whole[0];
    }
    if (finite && spread)
        return true;
    if (!strict)
        return false;
    for (int i = 0; i < n; i++)
        requireFinite(whole[i], "position", members[i], b);
    throw OpenMMException(className + ": the particles of body " + to_string(b) + " all sit at one point (have the "
            "Context's positions been set?); an explicit body takes its shape from the positions");
}

bool RigidBodySystem::shapeBody(int b, const vector<Vec3>& positions, const StepGeometry& geometry, bool strict,
                                double constraintTolerance) {
    if (!canShape(b, positions, geometry, strict))
        return false;
    vector<Vec3> whole(getBodySize(b));
    assemble(b, positions, geometry, whole.data());
    // The constraints inside the body hold in its shape: the positions are taken with them applied, as a
    // constrained integrator applies them to the positions it is given.
    if (!internalConstraints[b].empty())
        applyInternalConstraints(b, whole, constraintTolerance);
    vector<Vector3> centred;
    centreOfMass(b, whole.data(), centred);
    setShape(b, centred);
    return true;
}

void RigidBodySystem::applyInternalConstraints(int b, vector<Vec3>& whole, double tolerance) const {
    // Positions within the constraint tolerance (relative distance error, as OpenMM's) are left as
    // they are, as a constrained integrator leaves them.
    const int* members = getBodyParticles(b);
    bool within = true;
    for (const InternalConstraint& constraint : internalConstraints[b]) {
        const Vec3 separation = whole[constraint.first] - whole[constraint.second];
        within = within && fabs(sqrt(separation.dot(separation)) - constraint.distance) <= tolerance*constraint.distance;
    }
    if (within)
        return;
    // SHAKE (J.-P. Ryckaert, G. Ciccotti and H. J. C. Berendsen, J. Comput. Phys. 23, 327 (1977)) on the
    // body's particles alone: each constraint in turn moves its two particles along their separation in
    // the given positions, in inverse proportion to their masses, until every distance holds to 1e-12
    // (relative), far inside any tolerance. Its fixed point is the mass-weighted nearest constrained
    // geometry to first order.
    const vector<Vec3> given = whole;
    const InternalConstraint* failing = &internalConstraints[b][0];
    const int maxIterations = 10000;
    for (int iteration = 0; iteration < maxIterations; iteration++) {
        bool converged = true;
        for (const InternalConstraint& constraint : internalConstraints[b]) {
            const Vec3 separation = whole[constraint.first] - whole[constraint.second];
            const double target = constraint.distance*constraint.distance;
            const double error = target - separation.dot(separation);
            if (fabs(error) <= 2e-12*target)
                continue;
            converged = false;
            failing = &constraint;
            const Vec3 direction = given[constraint.first] - given[constraint.second];
            const double w1 = 1.0/masses[members[constraint.first]], w2 = 1.0/masses[members[constraint.second]];
            const double projection = separation.dot(direction);
            if (!(projection > 0.0)) {
                iteration = maxIterations;  // turned by 90 degrees or more from the given separation: SHAKE cannot go on
                break;
            }
            const double g = error/(2.0*(w1 + w2)*projection);
            whole[constraint.first] += direction*(g*w1);
            whole[constraint.second] -= direction*(g*w2);
        }
        if (converged)
            return;
    }
    const InternalConstraint& constraint = *failing;
    const Vec3 separation = given[constraint.first] - given[constraint.second];
    throw OpenMMException(className + ": the constraints inside body " + to_string(b) + " cannot be applied to the positions "
            "that give it its shape (SHAKE did not converge; constraint " + to_string(constraint.index) + " holds particles " +
            to_string(members[constraint.first]) + " and " + to_string(members[constraint.second]) + " at " +
            to_string(constraint.distance) + " nm, the positions put them " + to_string(sqrt(separation.dot(separation))) +
            " nm apart); set positions closer to the constraints, or remove them");
}

void RigidBodySystem::addBody(const vector<int>& members) {
    particles.insert(particles.end(), members.begin(), members.end());
    bodyStart.push_back(particles.size());
    bodyCoordinates.resize(particles.size(), Vector3{0.0, 0.0, 0.0});
    assemblyOrder.resize(particles.size(), 0);
    assemblyNeighbour.resize(particles.size(), -1);
    longestLink.push_back(0.0);
    bodyMass.push_back(0.0);
    RigidShape point = {RigidKindPoint, -1, {0.0, 0.0, 0.0}};
    shapes.push_back(point);
    massMoments.push_back(point);
    inertiaScale.insert(inertiaScale.end(), {1.0, 1.0, 1.0});
    shapeKnown.push_back(0);
    handednessOpen.push_back(0);
}

RigidBodySystem::RigidBodySystem(const System& system, const vector<vector<int> >& explicitBodies, bool useExplicit,
                                 const string& className, double minimumMoment) : className(className), minimumMoment(minimumMoment) {
    const int numParticles = system.getNumParticles();
    masses.resize(numParticles);
    for (int i = 0; i < numParticles; i++)
        masses[i] = system.getParticleMass(i);
    bodyOfParticle.assign(numParticles, -1);
    bodyStart.push_back(0);
    vector<vector<double> > pairDistances;
    if (useExplicit) {
        for (size_t b = 0; b < explicitBodies.size(); b++) {
            const vector<int>& members = explicitBodies[b];
            if (members.empty())
                throw OpenMMException(className + ": body " + to_string(b) + " has no particles");
            for (int p : members) {
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
            addBody(members);
        }
        pairDistances.resize(explicitBodies.size());
    }
    else
        findConstraintBodies(system, pairDistances);
    for (int b = 0; b < getNumBodies(); b++)
        checkBody(system, b);

    // Constraints inside a body are implied by its rigidity; those among free particles stay.
    internalConstraints.resize(getNumBodies());
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
            const int* first = getBodyParticles(bi);
            const int* last = first + getBodySize(bi);
            internalConstraints[bi].push_back({c, (int) (find(first, last, i) - first), (int) (find(first, last, j) - first), distance});
        }
        else {
            auto describe = [](int particle, int body) {
                return "particle " + to_string(particle) + (body == -1 ? " (free)" : " (body " + to_string(body) + ")");
            };
            throw OpenMMException(className + ": constraint " + to_string(c) + " joins " + describe(i, bi) + " and " +
                    describe(j, bj) + "; a constraint may not connect a rigid body to anything outside it");
        }
    }
    for (int b = 0; b < getNumBodies(); b++)
        if (!pairDistances[b].empty())
            shapeFromDistances(b, pairDistances[b]);
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
    for (int b = 0; b < getNumBodies(); b++) {
        bodySets[AllBodies].push_back(b);
        bodySets[FastBodies].push_back(b);
    }
}

void RigidBodySystem::setFastBodies(const vector<char>& reached) {
    bodySets[FastBodies].clear();
    bodySets[SlowBodies].clear();
    for (int b = 0; b < getNumBodies(); b++) {
        const int* members = getBodyParticles(b);
        const bool fast = any_of(members, members + getBodySize(b), [&](int p) { return reached[p] != 0; });
        bodySets[fast ? FastBodies : SlowBodies].push_back(b);
    }
}

void RigidBodySystem::findConstraintBodies(const System& system, vector<vector<double> >& pairDistances) {
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
        int b = getNumBodies();
        for (int p : members)
            bodyOfParticle[p] = b;
        addBody(members);
        // When every pair is constrained the distances fix the shape.
        map<pair<int, int>, double> distances;
        for (int c : constraints) {
            int i, j;
            double distance;
            system.getConstraintParameters(c, i, j, distance);
            distances[{min(i, j), max(i, j)}] = distance;
        }
        pairDistances.emplace_back();
        if ((int) distances.size() == n*(n - 1)/2) {
            vector<double>& pairs = pairDistances.back();
            pairs.resize(n*n, 0.0);
            for (int i = 0; i < n; i++)
                for (int j = i + 1; j < n; j++)
                    pairs[i*n + j] = pairs[j*n + i] = distances[{members[i], members[j]}];
        }
    }
}

void RigidBodySystem::checkBody(const System& system, int index) {
    const int* members = getBodyParticles(index);
    for (int i = 0; i < getBodySize(index); i++) {
        const int p = members[i];
        if (system.isVirtualSite(p))
            throw OpenMMException(className + ": particle " + to_string(p) + " of body " + to_string(index) +
                    " is a virtual site; virtual sites follow their parent particles and cannot be body members");
        if (masses[p] == 0.0)
            throw OpenMMException(className + ": particle " + to_string(p) + " of body " + to_string(index) +
                    " has zero mass; every body member must be massive");
        bodyMass[index] += masses[p];
    }
}

void RigidBodySystem::shapeFromDistances(int b, const vector<double>& pairDistances) {
    // Classical multidimensional scaling: the centred Gram matrix -1/2 J D^2 J of the constraint
    // distances has rank <= 3, and its leading eigenvectors scaled by sqrt(eigenvalue) are coordinates
    // reproducing every distance (Torgerson, Psychometrika 17, 401 (1952)).
    const int n = getBodySize(b);
    vector<double> gram(n*n), rowMean(n, 0.0);
    double mean = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double d2 = pairDistances[i*n + j]*pairDistances[i*n + j];
            rowMean[i] += d2/n;
            mean += d2/(n*n);
        }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double d2 = pairDistances[i*n + j]*pairDistances[i*n + j];
            gram[i*n + j] = -0.5*(d2 - rowMean[i] - rowMean[j] + mean);
        }
    vector<double> values, vectors;
    symmetricEigen(gram, n, values, vectors);
    vector<Vec3> coordinates(n);
    for (int k = 0; k < min(3, n); k++) {
        int column = n - 1 - k;
        double scale = sqrt(max(values[column], 0.0));
        for (int i = 0; i < n; i++)
            coordinates[i][k] = vectors[i*n + column]*scale;
    }
    vector<Vector3> centred;
    centreOfMass(b, coordinates.data(), centred);
    setShape(b, centred);
    // Distances do not tell a three-dimensional shape from its mirror image; the first fit to
    // positions does. Planar and linear shapes are their own mirror images up to a rotation.
    const double* moment = getMoments(b);
    double planarity = fabs(moment[2] - moment[1] - moment[0]);
    handednessOpen[b] = (getKind(b) != RigidKindPoint && getKind(b) != RigidKindLinear && planarity > 1e-10*moment[2]);
}

int RigidBodySystem::getNumDegreesOfFreedom() const {
    int dof = 3*freeParticles.size() - numFreeConstraints;
    for (const RigidShape& shape : shapes)
        dof += 3 + (shape.kind == RigidKindPoint ? 0 : shape.kind == RigidKindLinear ? 2 : 3);
    if (removesCenterOfMassMotion)
        dof -= 3;
    return dof;
}

} // namespace OpenMMRigid
