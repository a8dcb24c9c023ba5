#ifndef OPENMMRIGID_TESTS_RIGID_BODY_TEST_SYSTEMS_H_
#define OPENMMRIGID_TESTS_RIGID_BODY_TEST_SYSTEMS_H_

/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The fixtures of the physics suites (TestRigidBodyIntegrator.h,             *
 * TestRigidBodyThermostats.h, TestSerialization.cpp): small rigid molecules  *
 * and the systems built from them (isolated clusters, PME water boxes, a     *
 * mixed system), the exact free motion of a body, the runs and measurements  *
 * the tests share, and the runner every platform's main() calls.             *
 *                                                                            *
 * The small clusters interact through a CustomBondForce over all            *
 * intermolecular pairs (Lennard-Jones + Coulomb, no cutoff), which every     *
 * platform evaluates in double precision; the CPU platform's NonbondedForce  *
 * works in single precision, whose rounding noise would hide the 1e-10 and   *
 * 1e-8 checks. The water boxes use NonbondedForce with PME as a user would.  *
 * -------------------------------------------------------------------------- */

#include "RandomRotation.h"
#include "RigidBodyBussiIntegrator.h"
#include "RigidBodyIntegrator.h"
#include "RigidBodyLangevinIntegrator.h"
#include "numerics/FreeRotor.h"
#include "openmm/CMMotionRemover.h"
#include "openmm/Context.h"
#include "openmm/CustomBondForce.h"
#include "openmm/CustomExternalForce.h"
#include "openmm/HarmonicAngleForce.h"
#include "openmm/HarmonicBondForce.h"
#include "openmm/LangevinMiddleIntegrator.h"
#include "openmm/LocalEnergyMinimizer.h"
#include "openmm/NonbondedForce.h"
#include "openmm/OpenMMException.h"
#include "openmm/PeriodicTorsionForce.h"
#include "openmm/Platform.h"
#include "openmm/State.h"
#include "openmm/System.h"
#include "openmm/VerletIntegrator.h"
#include "openmm/VirtualSite.h"
#include "openmm/internal/AssertionUtilities.h"
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

extern "C" void registerKernelFactories();

namespace RigidBodyIntegratorTests {

// Scoped to the tests (as OpenMM's shared test headers are written, without leaking into includers).
using namespace OpenMM;
using namespace OpenMMRigid;
using std::string;
using std::vector;

const double boltzmann = 0.00831446261815324;   // kJ/mol/K
const double coulombConstant = 138.935456;      // kJ mol^-1 nm e^-2
const double rigidityTolerance = 1e-12;         // nm

std::map<string, string> platformProperties;    // set by the platform file
/**
 * Where the water boxes are minimised and equilibrated, if not on the platform under test (set by
 * the platform file): OpenMM's energy minimiser crashes on PoCL's OpenCL.
 */
Platform* preparationPlatform = nullptr;
/**
 * The relative accuracy to which the platform's solver meets the constraints among free particles,
 * whatever tolerance it is given, if that is coarser than the tolerance (set by the platform file):
 * OpenMM's SHAKE on OpenCL leaves about 1.5e-8 in double precision (stock VerletIntegrator, asked
 * for 1e-9, measured the same).
 */
double constraintSolverAccuracy = 0.0;
/** The number of 2 fs steps of the water boxes' NVE runs (set by the platform file: longer where they are cheap). */
int waterSteps = 300;

/** A short message with full precision numbers. */
template <class... Args>
string message(const Args&... args) {
    std::stringstream s;
    s.precision(6);
    (s << ... << args);
    return s.str();
}

void check(bool condition, const string& what) {
    if (!condition)
        throw OpenMMException("Assertion failure: " + what);
}


// ------------------------------------------------------------------------------------------------
// Small rigid molecules
// ------------------------------------------------------------------------------------------------

struct Molecule {
    string name;
    vector<double> masses;
    vector<Vec3> coordinates;  // nm, any frame
    vector<double> charges, sigmas, epsilons;
    bool isBody;
};

Molecule waterLike() {
    double angle = 104.52*M_PI/180.0, oh = 0.09572;
    return {"water", {15.999, 1.008, 1.008},
            {Vec3(0, 0, 0), Vec3(oh*sin(angle/2), oh*cos(angle/2), 0), Vec3(-oh*sin(angle/2), oh*cos(angle/2), 0)},
            {-0.834, 0.417, 0.417}, {0.315, 0.1, 0.1}, {0.636, 0.0, 0.0}, true};
}

Molecule ammoniaLike() {  // a symmetric top
    Molecule m = {"ammonia", {14.007, 1.008, 1.008, 1.008}, {Vec3(0, 0, 0.0381)}, {-0.9, 0.3, 0.3, 0.3},
                  {0.325, 0.1, 0.1, 0.1}, {0.711, 0.0, 0.0, 0.0}, true};
    for (int k = 0; k < 3; k++)
        m.coordinates.push_back(Vec3(0.0939*cos(2*M_PI*k/3), 0.0939*sin(2*M_PI*k/3), 0.0));
    return m;
}

Molecule methaneLike() {  // a spherical top
    double a = 0.109/sqrt(3.0);
    return {"methane", {12.011, 1.008, 1.008, 1.008, 1.008},
            {Vec3(0, 0, 0), Vec3(a, a, a), Vec3(a, -a, -a), Vec3(-a, a, -a), Vec3(-a, -a, a)},
            {-0.24, 0.06, 0.06, 0.06, 0.06}, {0.35, 0.25, 0.25, 0.25, 0.25}, {0.276, 0.125, 0.125, 0.125, 0.125}, true};
}

Molecule carbonDioxide() {  // linear triatomic
    return {"co2", {12.011, 15.999, 15.999}, {Vec3(0, 0, 0), Vec3(0, 0, 0.116), Vec3(0, 0, -0.116)},
            {0.7, -0.35, -0.35}, {0.28, 0.305, 0.305}, {0.224, 0.657, 0.657}, true};
}

Molecule carbonMonoxide() {  // linear diatomic
    return {"co", {12.011, 15.999}, {Vec3(0, 0, 0), Vec3(0, 0, 0.1128)}, {0.02, -0.02}, {0.33, 0.31}, {0.4, 0.5}, true};
}

Molecule sodium() {  // single-particle body
    return {"sodium", {22.99}, {Vec3()}, {1.0}, {0.25}, {0.36}, true};
}

Molecule chloride() {  // free particle
    return {"chloride", {35.45}, {Vec3()}, {-1.0}, {0.44}, {0.42}, false};
}

Molecule argon() {  // free particle
    return {"argon", {39.948}, {Vec3()}, {0.0}, {0.34}, {0.996}, false};
}

Molecule benzene() {  // planar symmetric top
    Molecule m = {"benzene", {}, {}, {}, {}, {}, true};
    for (int k = 0; k < 12; k++) {
        double r = (k < 6 ? 0.1397 : 0.1397 + 0.1084), phi = k*M_PI/3;
        m.masses.push_back(k < 6 ? 12.011 : 1.008);
        m.coordinates.push_back(Vec3(r*cos(phi), r*sin(phi), 0.0));
        m.charges.push_back(k < 6 ? -0.115 : 0.115);
        m.sigmas.push_back(k < 6 ? 0.355 : 0.242);
        m.epsilons.push_back(k < 6 ? 0.29288 : 0.12552);
    }
    return m;
}

/** A uniformly distributed rotation (a fresh normal distribution on rng for its four deviates). */
Matrix3 randomRotation(std::mt19937_64& rng) {
    std::normal_distribution<double> normal;
    return RigidBodyTestSupport::randomRotation([&]() { return normal(rng); });
}

Vec3 rotate(const Matrix3& m, const Vec3& v) {
    return Vec3(m[0][0]*v[0] + m[0][1]*v[1] + m[0][2]*v[2], m[1][0]*v[0] + m[1][1]*v[1] + m[1][2]*v[2],
                m[2][0]*v[0] + m[2][1]*v[1] + m[2][2]*v[2]);
}

/** A System under construction with its state, bodies and the data the pair force needs. */
struct Scene {
    std::shared_ptr<System> system = std::make_shared<System>();
    vector<Vec3> positions, velocities;
    vector<vector<int> > bodies;
    vector<int> free;
    vector<double> masses, charges, sigmas, epsilons;
    vector<int> molecule;  // molecule index of each particle
    int numMolecules = 0;
};

Vec3 centreOf(const vector<double>& masses, const vector<Vec3>& points) {
    Vec3 sum;
    double total = 0;
    for (size_t i = 0; i < masses.size(); i++) {
        sum += points[i]*masses[i];
        total += masses[i];
    }
    return sum/total;
}

/** The symmetric eigen-decomposition of a 3x3 matrix by cyclic Jacobi rotations (ascending values). */
void jacobiEigen(double a[3][3], double values[3], double vectors[3][3]) {
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            vectors[i][j] = (i == j);
    for (int sweep = 0; sweep < 100; sweep++) {
        double off = a[0][1]*a[0][1] + a[0][2]*a[0][2] + a[1][2]*a[1][2];
        if (off == 0.0)
            break;
        for (int p = 0; p < 2; p++)
            for (int q = p + 1; q < 3; q++) {
                if (a[p][q] == 0.0)
                    continue;
                double theta = (a[q][q] - a[p][p])/(2*a[p][q]);
                double t = (theta >= 0 ? 1.0 : -1.0)/(fabs(theta) + sqrt(1 + theta*theta));
                double c = 1/sqrt(1 + t*t), s = t*c;
                for (int k = 0; k < 3; k++) {
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c*akp - s*akq;
                    a[k][q] = s*akp + c*akq;
                }
                for (int k = 0; k < 3; k++) {
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c*apk - s*aqk;
                    a[q][k] = s*apk + c*aqk;
                }
                for (int k = 0; k < 3; k++) {
                    double vkp = vectors[k][p], vkq = vectors[k][q];
                    vectors[k][p] = c*vkp - s*vkq;
                    vectors[k][q] = s*vkp + c*vkq;
                }
            }
    }
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int i, int j) { return a[i][i] < a[j][j]; });
    double sorted[3][3];
    for (int k = 0; k < 3; k++) {
        values[k] = a[order[k]][order[k]];
        for (int i = 0; i < 3; i++)
            sorted[i][k] = vectors[i][order[k]];
    }
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            vectors[i][k] = sorted[i][k];
}

/** The inertia tensor of points (relative to their centre of mass). */
void inertiaTensor(const vector<double>& masses, const vector<Vec3>& relative, double inertia[3][3]) {
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            inertia[i][j] = 0;
    for (size_t k = 0; k < masses.size(); k++) {
        const Vec3& r = relative[k];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                inertia[i][j] += masses[k]*((i == j ? r.dot(r) : 0.0) - r[i]*r[j]);
    }
}

/**
 * The kind of a rigid body, from the principal moments of inertia of its particles about their
 * centre of mass: "point" (one particle, or all moments zero), "linear" (one zero moment),
 * "spherical" (three equal), "symmetric" (two equal) or "asymmetric". Moments within 1e-10 of the
 * largest count as equal (or zero): the molecules here are exact by construction, and rounding
 * leaves 1e-16.
 */
string bodyKind(const vector<double>& masses, const vector<Vec3>& positions) {
    if (masses.size() < 2)
        return "point";
    Vec3 centre = centreOf(masses, positions);
    vector<Vec3> relative;
    for (const Vec3& r : positions)
        relative.push_back(r - centre);
    double inertia[3][3], moments[3], axes[3][3];
    inertiaTensor(masses, relative, inertia);
    jacobiEigen(inertia, moments, axes);  // ascending
    const double tolerance = 1e-10*moments[2];
    if (moments[2] <= tolerance)
        return "point";
    if (moments[0] <= tolerance)
        return "linear";
    const bool low = fabs(moments[1] - moments[0]) <= tolerance, high = fabs(moments[2] - moments[1]) <= tolerance;
    if (low && high)
        return "spherical";
    return (low || high ? "symmetric" : "asymmetric");
}

/** The kind of body `body` of a system with these masses and positions (see bodyKind()). */
string bodyKind(const vector<double>& masses, const vector<Vec3>& positions, const vector<int>& body) {
    vector<double> m;
    vector<Vec3> r;
    for (int p : body) {
        m.push_back(masses[p]);
        r.push_back(positions[p]);
    }
    return bodyKind(m, r);
}

/**
 * The degrees of freedom of a system moved by a rigid-body integrator with these bodies, counted from
 * the System: 3 per free particle with mass, less one per constraint between two free particles, plus
 * 3 translational and 0 (one particle), 2 (linear) or 3 rotational ones per body (its kind from the
 * positions), less 3 with a CMMotionRemover.
 */
int countDegreesOfFreedom(const System& system, const vector<vector<int> >& bodies, const vector<Vec3>& positions) {
    vector<double> masses;
    for (int i = 0; i < system.getNumParticles(); i++)
        masses.push_back(system.getParticleMass(i));
    vector<bool> inBody(masses.size(), false);
    int dof = 0;
    for (const vector<int>& body : bodies) {
        for (int p : body)
            inBody[p] = true;
        const string kind = bodyKind(masses, positions, body);
        dof += 3 + (kind == "point" ? 0 : kind == "linear" ? 2 : 3);
    }
    for (size_t i = 0; i < masses.size(); i++)
        if (!inBody[i] && masses[i] > 0.0)
            dof += 3;
    for (int c = 0; c < system.getNumConstraints(); c++) {
        int i, j;
        double length;
        system.getConstraintParameters(c, i, j, length);
        if (!inBody[i] && !inBody[j])
            dof--;
    }
    for (int f = 0; f < system.getNumForces(); f++)
        if (dynamic_cast<const CMMotionRemover*>(&system.getForce(f)) != nullptr)
            dof -= 3;
    return dof;
}

/**
 * The kinetic energies of the centre-of-mass motion of the bodies and of the free particles
 * (translational), and of the bodies' motion about their centres of mass (rotational), of these
 * velocities. The sums run in the order of the integrator's own (bodies in order, each from its
 * centre-of-mass velocity sum m v / M, then the free particles in index order), so that on the
 * Reference platform they are the sums the integrator forms, bit for bit.
 */
void rigidKineticEnergies(const vector<double>& masses, const vector<vector<int> >& bodies, const vector<Vec3>& velocities,
                          double& translational, double& rotational) {
    translational = rotational = 0.0;
    vector<bool> inBody(masses.size(), false);
    for (const vector<int>& body : bodies) {
        double mass = 0.0;
        for (int p : body) {
            mass += masses[p];
            inBody[p] = true;
        }
        Vec3 velocity;
        for (int p : body)
            for (int k = 0; k < 3; k++)
                velocity[k] += masses[p]*velocities[p][k]/mass;
        translational += 0.5*mass*velocity.dot(velocity);
        for (int p : body) {
            Vec3 relative = velocities[p] - velocity;
            rotational += 0.5*masses[p]*relative.dot(relative);
        }
    }
    for (size_t p = 0; p < masses.size(); p++)
        if (!inBody[p] && masses[p] > 0.0)
            translational += 0.5*masses[p]*velocities[p].dot(velocities[p]);
}

/** The total of rigidKineticEnergies(): translational + rotational. */
double rigidKineticEnergy(const vector<double>& masses, const vector<vector<int> >& bodies, const vector<Vec3>& velocities) {
    double translational, rotational;
    rigidKineticEnergies(masses, bodies, velocities, translational, rotational);
    return translational + rotational;
}

/**
 * Add a molecule at centre with a random orientation and thermal rigid velocities (a body), or at
 * rest relative to a thermal centre-of-mass velocity (free atoms).
 */
void addMolecule(Scene& scene, const Molecule& molecule, Vec3 centre, std::mt19937_64& rng, double temperature,
                 bool randomOrientation = true) {
    std::normal_distribution<double> normal;
    Matrix3 rotation = randomOrientation ? randomRotation(rng) : identityMatrix();
    int n = molecule.masses.size();
    double total = 0;
    for (double m : molecule.masses)
        total += m;
    Vec3 com = centreOf(molecule.masses, molecule.coordinates);
    vector<Vec3> relative;
    for (int k = 0; k < n; k++)
        relative.push_back(rotate(rotation, molecule.coordinates[k] - com));
    double scale = sqrt(boltzmann*temperature/total);
    Vec3 velocity(scale*normal(rng), scale*normal(rng), scale*normal(rng));
    Vec3 omega;
    if (n > 1) {
        double inertia[3][3], moments[3], axes[3][3];
        inertiaTensor(molecule.masses, relative, inertia);
        jacobiEigen(inertia, moments, axes);
        for (int k = 0; k < 3; k++)
            if (moments[k] > 1e-9*moments[2]) {
                double w = sqrt(boltzmann*temperature/moments[k])*normal(rng);
                omega += Vec3(axes[0][k], axes[1][k], axes[2][k])*w;
            }
    }
    vector<int> indices;
    for (int k = 0; k < n; k++) {
        indices.push_back(scene.system->addParticle(molecule.masses[k]));
        scene.positions.push_back(centre + relative[k]);
        scene.velocities.push_back(velocity + omega.cross(relative[k]));
        scene.masses.push_back(molecule.masses[k]);
        scene.charges.push_back(molecule.charges[k]);
        scene.sigmas.push_back(molecule.sigmas[k]);
        scene.epsilons.push_back(molecule.epsilons[k]);
        scene.molecule.push_back(scene.numMolecules);
    }
    scene.numMolecules++;
    if (molecule.isBody)
        scene.bodies.push_back(indices);
    else
        scene.free.insert(scene.free.end(), indices.begin(), indices.end());
}

/** Lennard-Jones + Coulomb between every pair of particles of different molecules, in double precision. */
void addPairForce(Scene& scene, const std::set<std::pair<int, int> >& excluded = {}) {
    CustomBondForce* pairs = new CustomBondForce("4*epsilon*((sigma/r)^12 - (sigma/r)^6) + coulomb*qq/r");
    pairs->addGlobalParameter("coulomb", coulombConstant);
    pairs->addPerBondParameter("qq");
    pairs->addPerBondParameter("sigma");
    pairs->addPerBondParameter("epsilon");
    int n = scene.masses.size();
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            if (scene.molecule[i] != scene.molecule[j] && excluded.count({i, j}) == 0)
                pairs->addBond(i, j, {scene.charges[i]*scene.charges[j], 0.5*(scene.sigmas[i] + scene.sigmas[j]),
                                      sqrt(scene.epsilons[i]*scene.epsilons[j])});
    scene.system->addForce(pairs);
}

/**
 * An isolated cluster: molecules of every kind on a grid (spacing 0.5 nm), the last two sites free
 * atoms. drift (nm/ps) is added to every velocity and spin (rad/ps) turns the whole cluster about z.
 */
Scene makeCluster(unsigned seed, int nx, int ny, int nz, bool withForces, Vec3 drift = Vec3(), double spin = 0.0) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal;
    vector<std::function<Molecule()> > kinds = {waterLike, ammoniaLike, methaneLike, carbonDioxide, carbonMonoxide, sodium};
    int sites = nx*ny*nz;
    vector<std::function<Molecule()> > plan;
    for (int k = 0; k < sites - 2; k++)
        plan.push_back(k < 2*(int) kinds.size() ? kinds[k%kinds.size()] : waterLike);
    plan.push_back(chloride);
    plan.push_back(argon);
    Scene scene;
    int site = 0;
    for (int i = 0; i < nx; i++)
        for (int j = 0; j < ny; j++)
            for (int k = 0; k < nz; k++, site++) {
                Vec3 jitter(0.02*normal(rng), 0.02*normal(rng), 0.02*normal(rng));
                addMolecule(scene, plan[site](), Vec3(i, j, k)*0.5 + jitter, rng, 300.0);
            }
    Vec3 centre = centreOf(scene.masses, scene.positions);
    for (size_t i = 0; i < scene.positions.size(); i++)
        scene.velocities[i] += drift + Vec3(0, 0, spin).cross(scene.positions[i] - centre);
    if (withForces)
        addPairForce(scene);
    return scene;
}


// ------------------------------------------------------------------------------------------------
// Running and measuring
// ------------------------------------------------------------------------------------------------

struct Run {
    std::unique_ptr<RigidBodyIntegrator> integrator;
    std::unique_ptr<Context> context;
};

Run startRigid(const Scene& scene, Platform& platform, double dt, RigidBodyIntegrator::RotationMethod method,
               bool explicitBodies = true, RigidBodyIntegrator::Splitting splitting = RigidBodyIntegrator::Verlet) {
    Run run;
    run.integrator.reset(explicitBodies ? new RigidBodyIntegrator(dt, scene.bodies) : new RigidBodyIntegrator(dt));
    run.integrator->setRotationMethod(method);
    run.integrator->setSplitting(splitting);
    run.context.reset(new Context(*scene.system, *run.integrator, platform, platformProperties));
    run.context->setPositions(scene.positions);
    run.context->setVelocities(scene.velocities);
    return run;
}

const vector<RigidBodyIntegrator::Splitting> allSplittings = {RigidBodyIntegrator::Verlet, RigidBodyIntegrator::Omelyan2,
                                                              RigidBodyIntegrator::Yoshida4, RigidBodyIntegrator::Omelyan4};

string splittingName(RigidBodyIntegrator::Splitting splitting) {
    const char* names[] = {"Verlet", "Omelyan2", "Yoshida4", "Omelyan4"};
    return names[splitting];
}

/** The force evaluations of a step of each splitting: one after each of its drifts. */
int forceEvaluations(RigidBodyIntegrator::Splitting splitting) {
    const std::map<RigidBodyIntegrator::Splitting, int> evaluations = {
        {RigidBodyIntegrator::Verlet, 1}, {RigidBodyIntegrator::Omelyan2, 2}, {RigidBodyIntegrator::Yoshida4, 3},
        {RigidBodyIntegrator::Omelyan4, 4}};
    return evaluations.at(splitting);
}

/**
 * The order of a splitting in dt. Omelyan4's fourth order needs exact drifts: NO_SQUISH's rotation is
 * a second-order approximation of the free rotation, which the scheme does not compose into a
 * higher order, whereas Yoshida4, a composition of symmetric Verlet steps, is fourth order whatever
 * second-order symmetric drift the steps use.
 */
int splittingOrder(RigidBodyIntegrator::Splitting splitting, RigidBodyIntegrator::RotationMethod method) {
    if (splitting == RigidBodyIntegrator::Yoshida4)
        return 4;
    if (splitting == RigidBodyIntegrator::Omelyan4 && method == RigidBodyIntegrator::Exact)
        return 4;
    return 2;
}

vector<Vec3> positionsOf(Context& context) {
    return context.getState(State::Positions).getPositions();
}

vector<Vec3> velocitiesOf(Context& context) {
    return context.getState(State::Velocities).getVelocities();
}

double totalEnergy(Context& context) {
    State state = context.getState(State::Energy);
    return state.getPotentialEnergy() + state.getKineticEnergy();
}

double maxDifference(const vector<Vec3>& a, const vector<Vec3>& b) {
    double worst = 0;
    for (size_t i = 0; i < a.size(); i++)
        for (int k = 0; k < 3; k++)
            worst = std::max(worst, fabs(a[i][k] - b[i][k]));
    return worst;
}

double rmsDifference(const vector<Vec3>& a, const vector<Vec3>& b) {
    double sum = 0;
    for (size_t i = 0; i < a.size(); i++)
        sum += (a[i] - b[i]).dot(a[i] - b[i]);
    return sqrt(sum/a.size());
}

vector<Vec3> runCluster(const Scene& scene, Platform& platform, double dt, int steps, RigidBodyIntegrator::RotationMethod method,
                        RigidBodyIntegrator::Splitting splitting = RigidBodyIntegrator::Verlet) {
    Run run = startRigid(scene, platform, dt, method, true, splitting);
    run.integrator->step(steps);
    return positionsOf(*run.context);
}

/** The least-squares slope of y against x, its standard error and the rms residual about the line. */
void fitLine(const vector<double>& x, const vector<double>& y, double& slope, double& error, double& rms) {
    int n = x.size();
    double mx = 0, my = 0;
    for (int i = 0; i < n; i++) {
        mx += x[i]/n;
        my += y[i]/n;
    }
    double sxx = 0, sxy = 0;
    for (int i = 0; i < n; i++) {
        sxx += (x[i] - mx)*(x[i] - mx);
        sxy += (x[i] - mx)*(y[i] - my);
    }
    slope = sxy/sxx;
    double residual = 0;
    for (int i = 0; i < n; i++) {
        double r = y[i] - my - slope*(x[i] - mx);
        residual += r*r;
    }
    rms = sqrt(residual/n);
    error = sqrt(residual/(n - 2)/sxx);
}

/**
 * The drift of y against x from the means of `blocks` consecutive blocks: slope and standard error of
 * the line through the block means. Block means longer than the correlation time of the energy
 * fluctuations are nearly independent, so this error understates the uncertainty of the slope less
 * than that of a fit to every sample does; a wandering as slow as the whole run escapes it all the
 * same (testWaterEnergy() says by how much).
 */
void blockDrift(const vector<double>& x, const vector<double>& y, int blocks, double& slope, double& error) {
    int size = x.size()/blocks;
    vector<double> bx(blocks, 0.0), by(blocks, 0.0);
    for (int b = 0; b < blocks; b++)
        for (int i = b*size; i < (b + 1)*size; i++) {
            bx[b] += x[i]/size;
            by[b] += y[i]/size;
        }
    double rms;
    fitLine(bx, by, slope, error, rms);
}

/** Total energies every interval steps (the first at t = 0) and their times. */
void recordEnergies(Context& context, Integrator& integrator, int steps, int interval, vector<double>& times,
                    vector<double>& energies) {
    times.clear();
    energies.clear();
    for (int k = 0; k <= steps; k += interval) {
        if (k > 0)
            integrator.step(interval);
        times.push_back(k*integrator.getStepSize());
        energies.push_back(totalEnergy(context));
    }
}

double maxDeviation(const vector<double>& values) {
    double worst = 0;
    for (double v : values)
        worst = std::max(worst, fabs(v - values[0]));
    return worst;
}


string methodName(RigidBodyIntegrator::RotationMethod method) {
    return method == RigidBodyIntegrator::Exact ? "Exact" : "NoSquish";
}

string label(RigidBodyIntegrator::RotationMethod method, RigidBodyIntegrator::Splitting splitting) {
    return splittingName(splitting) + ", " + methodName(method);
}


// ------------------------------------------------------------------------------------------------
// The exact free motion
// ------------------------------------------------------------------------------------------------

/** The exact torque-free motion of one body, from its initial positions and velocities. */
class ExactBody {
public:
    ExactBody(const vector<double>& masses, const vector<Vec3>& positions, const vector<Vec3>& velocities) {
        centre = centreOf(masses, positions);
        velocity = centreOf(masses, velocities);
        vector<Vec3> relative;
        Vec3 angularMomentum;
        for (size_t i = 0; i < masses.size(); i++) {
            relative.push_back(positions[i] - centre);
            angularMomentum += relative[i].cross(velocities[i] - velocity)*masses[i];
        }
        if (masses.size() == 1) {
            bodyCoordinates.push_back(Vec3());
            return;
        }
        double inertia[3][3], moments[3], axes[3][3];
        inertiaTensor(masses, relative, inertia);
        jacobiEigen(inertia, moments, axes);
        double det = axes[0][0]*(axes[1][1]*axes[2][2] - axes[1][2]*axes[2][1]) -
                     axes[0][1]*(axes[1][0]*axes[2][2] - axes[1][2]*axes[2][0]) +
                     axes[0][2]*(axes[1][0]*axes[2][1] - axes[1][1]*axes[2][0]);
        if (det < 0)
            for (int i = 0; i < 3; i++)
                axes[i][0] = -axes[i][0];
        Matrix3 attitude;  // lab -> body: rows are the principal axes
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++)
                attitude[k][c] = axes[c][k];
        bool linear = moments[0] <= 1e-12*moments[2];
        Vector3 principal = {moments[0], moments[1], moments[2]}, omega;
        if (linear)
            principal[0] = 0.0;
        for (int k = 0; k < 3; k++) {
            double lk = attitude[k][0]*angularMomentum[0] + attitude[k][1]*angularMomentum[1] + attitude[k][2]*angularMomentum[2];
            omega[k] = (principal[k] > 0 ? lk/principal[k] : 0.0);
        }
        for (const Vec3& r : relative) {
            Vec3 b(attitude[0][0]*r[0] + attitude[0][1]*r[1] + attitude[0][2]*r[2],
                   attitude[1][0]*r[0] + attitude[1][1]*r[1] + attitude[1][2]*r[2],
                   attitude[2][0]*r[0] + attitude[2][1]*r[1] + attitude[2][2]*r[2]);
            if (linear)
                b = Vec3(b[0], 0, 0);
            bodyCoordinates.push_back(b);
        }
        rotor.reset(new FreeRotor(principal, omega, attitude));
    }
    /** Positions and velocities at time t. */
    void at(double t, vector<Vec3>& positions, vector<Vec3>& velocities) const {
        positions.clear();
        velocities.clear();
        Vec3 translated = centre + velocity*t;
        if (!rotor) {
            positions.push_back(translated);
            velocities.push_back(velocity);
            return;
        }
        Vector3 omega;
        Matrix3 a;
        rotor->evolve(t, omega, a);
        Vec3 labOmega(a[0][0]*omega[0] + a[1][0]*omega[1] + a[2][0]*omega[2],
                      a[0][1]*omega[0] + a[1][1]*omega[1] + a[2][1]*omega[2],
                      a[0][2]*omega[0] + a[1][2]*omega[1] + a[2][2]*omega[2]);
        for (const Vec3& b : bodyCoordinates) {
            Vec3 r(a[0][0]*b[0] + a[1][0]*b[1] + a[2][0]*b[2], a[0][1]*b[0] + a[1][1]*b[1] + a[2][1]*b[2],
                   a[0][2]*b[0] + a[1][2]*b[1] + a[2][2]*b[2]);  // A^T b
            positions.push_back(translated + r);
            velocities.push_back(velocity + labOmega.cross(r));
        }
    }
private:
    Vec3 centre, velocity;
    vector<Vec3> bodyCoordinates;
    std::shared_ptr<FreeRotor> rotor;
};

// ------------------------------------------------------------------------------------------------
// Constant temperature
// ------------------------------------------------------------------------------------------------

struct LangevinRun {
    std::unique_ptr<RigidBodyLangevinIntegrator> integrator;
    std::unique_ptr<Context> context;
};

LangevinRun startLangevin(const Scene& scene, Platform& platform, double temperature, double friction, double dt, int seed,
                          const std::map<string, string>& properties = platformProperties) {
    LangevinRun run;
    run.integrator.reset(new RigidBodyLangevinIntegrator(temperature, friction, dt, scene.bodies));
    run.integrator->setRandomNumberSeed(seed);
    run.context.reset(new Context(*scene.system, *run.integrator, platform, properties));
    run.context->setPositions(scene.positions);
    run.context->setVelocities(scene.velocities);
    return run;
}

/** The mean and the standard error of the mean of independent samples; the sample variance and its standard error. */
void sampleMoments(const vector<double>& x, double& mean, double& meanError, double& variance, double& varianceError) {
    const double n = x.size();
    mean = 0;
    for (double v : x)
        mean += v/n;
    double m2 = 0, m4 = 0;
    for (double v : x) {
        m2 += (v - mean)*(v - mean)/n;
        m4 += pow(v - mean, 4)/n;
    }
    variance = m2*n/(n - 1);
    meanError = sqrt(variance/n);
    varianceError = sqrt((m4 - m2*m2)/n);
}

struct BussiRun {
    std::unique_ptr<RigidBodyBussiIntegrator> integrator;
    std::unique_ptr<Context> context;
};

/**
 * A RigidBodyBussiIntegrator on the scene's bodies. With measure, the shadow work and the heat (the
 * thermostat's work) are measured from the first step.
 */
BussiRun startThermostat(const Scene& scene, Platform& platform, double temperature, double collisionTime, double dt, int seed,
                         const std::map<string, string>& properties = platformProperties, bool measure = false) {
    BussiRun run;
    run.integrator.reset(new RigidBodyBussiIntegrator(temperature, collisionTime, dt, scene.bodies));
    run.integrator->setRandomNumberSeed(seed);
    run.integrator->setMeasureShadowWork(measure);
    run.context.reset(new Context(*scene.system, *run.integrator, platform, properties));
    run.context->setPositions(scene.positions);
    run.context->setVelocities(scene.velocities);
    return run;
}

// ------------------------------------------------------------------------------------------------
// Rigid water boxes against VerletIntegrator + SETTLE
// ------------------------------------------------------------------------------------------------

/**
 * A cubic box of 4 x 4 x 4 rigid waters (TIP3P, or TIP4P-Ew with its massless M site), PME with a
 * switched 0.55 nm cutoff, minimised and thermalised at 300 K on the given platform.
 */
Scene makeWaterBox(Platform& platform, bool fourSite) {
    const int perSide = 4;
    const double spacing = 0.3107, size = perSide*spacing;  // 33.4 waters per nm^3
    const double oh = 0.09572, angle = 104.52*M_PI/180.0;
    const double qH = fourSite ? 0.52422 : 0.417, sigmaO = fourSite ? 0.316435 : 0.315061,
                 epsilonO = fourSite ? 0.680946 : 0.636386;
    const double mWeight = 0.106676721;  // TIP4P-Ew (OpenMM's tip4pew.xml): M = 0.786646558 O + 0.106676721 (H1 + H2)
    std::mt19937_64 rng(fourSite ? 44 : 33);
    Scene scene;
    System& system = *scene.system;
    NonbondedForce* nonbonded = new NonbondedForce();
    nonbonded->setNonbondedMethod(NonbondedForce::PME);
    nonbonded->setCutoffDistance(0.55);
    nonbonded->setUseSwitchingFunction(true);
    nonbonded->setSwitchingDistance(0.45);
    nonbonded->setEwaldErrorTolerance(1e-4);
    system.addForce(nonbonded);
    system.setDefaultPeriodicBoxVectors(Vec3(size, 0, 0), Vec3(0, size, 0), Vec3(0, 0, size));
    for (int i = 0; i < perSide; i++)
        for (int j = 0; j < perSide; j++)
            for (int k = 0; k < perSide; k++) {
                Matrix3 rotation = randomRotation(rng);
                Vec3 centre = Vec3(i + 0.5, j + 0.5, k + 0.5)*spacing;
                vector<Vec3> local = {Vec3(0, 0, 0), Vec3(oh*sin(angle/2), oh*cos(angle/2), 0),
                                      Vec3(-oh*sin(angle/2), oh*cos(angle/2), 0)};
                int o = system.addParticle(15.999);
                system.addParticle(1.008);
                system.addParticle(1.008);
                for (int a = 0; a < 3; a++) {
                    scene.positions.push_back(centre + rotate(rotation, local[a] - Vec3(0, 0.0065, 0)));
                    scene.masses.push_back(system.getParticleMass(o + a));
                }
                nonbonded->addParticle(fourSite ? 0.0 : -2*qH, sigmaO, epsilonO);
                nonbonded->addParticle(qH, 1.0, 0.0);
                nonbonded->addParticle(qH, 1.0, 0.0);
                system.addConstraint(o, o + 1, oh);
                system.addConstraint(o, o + 2, oh);
                system.addConstraint(o + 1, o + 2, 2*oh*sin(angle/2));
                vector<int> body = {o, o + 1, o + 2};
                if (fourSite) {
                    int m = system.addParticle(0.0);
                    system.setVirtualSite(m, new ThreeParticleAverageSite(o, o + 1, o + 2, 1 - 2*mWeight, mWeight, mWeight));
                    scene.positions.push_back(Vec3());
                    scene.masses.push_back(0.0);
                    nonbonded->addParticle(-2*qH, 1.0, 0.0);
                }
                int last = system.getNumParticles();
                for (int a = o; a < last; a++)
                    for (int b = a + 1; b < last; b++)
                        nonbonded->addException(a, b, 0.0, 1.0, 0.0);
                scene.bodies.push_back(body);
            }
    // Minimise and thermalise with constraints, then take the state.
    Platform& preparing = (preparationPlatform != nullptr ? *preparationPlatform : platform);
    const std::map<string, string> preparingProperties = (preparationPlatform != nullptr ? std::map<string, string>() : platformProperties);
    VerletIntegrator minimiser(0.001);
    minimiser.setConstraintTolerance(1e-10);
    Context context(system, minimiser, preparing, preparingProperties);
    context.setPositions(scene.positions);
    context.applyConstraints(1e-10);
    LocalEnergyMinimizer::minimize(context, 5.0, 100);
    LangevinMiddleIntegrator thermostat(300.0, 5.0, 0.002);
    thermostat.setRandomNumberSeed(fourSite ? 4 : 3);
    thermostat.setConstraintTolerance(1e-10);
    Context equilibration(system, thermostat, preparing, preparingProperties);
    equilibration.setPositions(context.getState(State::Positions).getPositions());
    equilibration.setVelocitiesToTemperature(300.0, 5);
    thermostat.step(300);
    context.setPositions(equilibration.getState(State::Positions).getPositions());
    context.setVelocities(equilibration.getState(State::Velocities).getVelocities());
    context.applyConstraints(1e-10);
    context.applyVelocityConstraints(1e-10);
    State state = context.getState(State::Positions | State::Velocities);
    scene.positions = state.getPositions();
    scene.velocities = state.getVelocities();
    return scene;
}

// ------------------------------------------------------------------------------------------------
// A mixed system
// ------------------------------------------------------------------------------------------------

/**
 * The bodies kept their shape since `start` (every intra-body distance to rigidityTolerance) and the
 * constraints among free particles hold, in length and in rate of change, to `tolerance`.
 */
void checkRigidAndConstrained(const Scene& scene, const vector<Vec3>& start, const vector<Vec3>& positions,
                              const vector<Vec3>& velocities, double tolerance) {
    for (size_t b = 0; b < scene.bodies.size(); b++) {
        const vector<int>& body = scene.bodies[b];
        for (size_t i = 0; i < body.size(); i++)
            for (size_t j = i + 1; j < body.size(); j++) {
                Vec3 now = positions[body[i]] - positions[body[j]], then = start[body[i]] - start[body[j]];
                double change = fabs(sqrt(now.dot(now)) - sqrt(then.dot(then)));
                check(change < rigidityTolerance, message("body ", b, ": the distance ", body[i], "-", body[j],
                      " changed by ", change, " nm"));
            }
    }
    for (int c = 0; c < scene.system->getNumConstraints(); c++) {
        int i, j;
        double length;
        scene.system->getConstraintParameters(c, i, j, length);
        Vec3 d = positions[i] - positions[j], dv = velocities[i] - velocities[j];
        double r = sqrt(d.dot(d));
        check(fabs(r/length - 1) <= std::max(tolerance, constraintSolverAccuracy), message("constraint ", c, ": ", r, " nm, not ", length, " (relative error ", r/length - 1, ")"));
        check(fabs(d.dot(dv)/r) <= 10*tolerance, message("constraint ", c, ": its length changes at ", d.dot(dv)/r, " nm/ps"));
    }
}

/**
 * An isolated cluster: a flexible four-carbon chain with one hydrogen per carbon (harmonic bonds,
 * angles and torsions; C-H bonds constrained, as HBonds does), rigid waters, a rigid benzene, a
 * rigid CO2, a Na+ body and a free Cl-.
 */
Scene makeMixed(std::set<std::pair<int, int> >& chainConstraints) {
    std::mt19937_64 rng(21);
    Scene scene;
    // The chain, built in a zigzag; its bonded terms are at their minimum in this geometry.
    Molecule chain = {"chain", {}, {}, {}, {}, {}, false};
    for (int k = 0; k < 4; k++) {
        Vec3 carbon(0.127*k, (k%2)*0.08, 0.0);
        chain.masses.push_back(12.011);
        chain.coordinates.push_back(carbon);
        chain.charges.push_back(-0.1);
        chain.sigmas.push_back(0.34);
        chain.epsilons.push_back(0.36);
    }
    for (int k = 0; k < 4; k++) {
        chain.masses.push_back(1.008);
        chain.coordinates.push_back(chain.coordinates[k] + Vec3(0.0, (k%2 ? 0.06 : -0.06), 0.085));
        chain.charges.push_back(0.1);
        chain.sigmas.push_back(0.26);
        chain.epsilons.push_back(0.07);
    }
    addMolecule(scene, chain, Vec3(0.6, 0.6, 0.6), rng, 300.0);
    std::normal_distribution<double> normal;
    for (int p : scene.free)  // thermal velocities for each atom of the flexible chain
        for (int k = 0; k < 3; k++)
            scene.velocities[p][k] = sqrt(boltzmann*300.0/scene.masses[p])*normal(rng);
    HarmonicBondForce* bonds = new HarmonicBondForce();
    HarmonicAngleForce* angles = new HarmonicAngleForce();
    PeriodicTorsionForce* torsions = new PeriodicTorsionForce();
    auto distance = [&](int i, int j) { Vec3 d = scene.positions[i] - scene.positions[j]; return sqrt(d.dot(d)); };
    auto angle = [&](int i, int j, int k) {
        Vec3 a = scene.positions[i] - scene.positions[j], b = scene.positions[k] - scene.positions[j];
        return acos(a.dot(b)/sqrt(a.dot(a)*b.dot(b)));
    };
    std::set<std::pair<int, int> > excluded;
    for (int k = 0; k < 4; k++) {
        scene.system->addConstraint(k, k + 4, distance(k, k + 4));
        chainConstraints.insert({k, k + 4});
        if (k < 3)
            bonds->addBond(k, k + 1, distance(k, k + 1), 2.5e5);
        if (k < 2)
            angles->addAngle(k, k + 1, k + 2, angle(k, k + 1, k + 2), 400.0);
        if (k > 0)
            angles->addAngle(k + 4, k, k - 1, angle(k + 4, k, k - 1), 300.0);
    }
    torsions->addTorsion(0, 1, 2, 3, 3, 0.0, 2.0);
    scene.system->addForce(bonds);
    scene.system->addForce(angles);
    scene.system->addForce(torsions);
    // Rigid and single-particle bodies around it; the free Cl- last.
    vector<Molecule> others = {benzene(), carbonDioxide(), sodium(), waterLike(), waterLike(), waterLike(),
                               waterLike(), waterLike(), waterLike(), chloride()};
    vector<Vec3> sites = {Vec3(0.2, 0.2, 1.1), Vec3(1.1, 0.2, 0.2), Vec3(0.2, 1.1, 0.2), Vec3(1.1, 1.1, 0.2),
                          Vec3(1.1, 0.2, 1.1), Vec3(0.2, 1.1, 1.1), Vec3(1.1, 1.1, 1.1), Vec3(0.6, 0.6, 1.3),
                          Vec3(0.6, 1.4, 0.6), Vec3(1.4, 0.6, 0.6)};
    for (size_t k = 0; k < others.size(); k++)
        addMolecule(scene, others[k], sites[k], rng, 300.0);
    addPairForce(scene, excluded);
    return scene;
}

// ------------------------------------------------------------------------------------------------
// Systems for bad input
// ------------------------------------------------------------------------------------------------

const vector<Vec3> smallPositions = {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.12, 0), Vec3(0.5, 0.5, 0.5),
                                     Vec3(0.6, 0.5, 0.5), Vec3(0.5, 0.65, 0.55)};

System* smallSystem() {
    System* system = new System();
    for (int i = 0; i < 6; i++)
        system->addParticle(1.0);
    return system;
}

/** Whether text names one of the indices as a particle or body. */
bool namesIndex(const string& text, const vector<int>& indices) {
    if (!std::regex_search(text, std::regex("particle|body", std::regex::icase)))
        return false;
    for (int index : indices)
        if (std::regex_search(text, std::regex("\\b" + std::to_string(index) + "\\b")))
            return true;
    return false;
}

// ------------------------------------------------------------------------------------------------
// Running a suite
// ------------------------------------------------------------------------------------------------

/**
 * Run each test, print "ok" with its time or "FAIL" with the message, and return the number of
 * failures. With OPENMMRIGID_TEST_FILTER set, only the tests whose names contain it, or one of its
 * parts separated by '|', run.
 */
int runTestList(const vector<std::pair<string, std::function<void()> > >& tests) {
    int failures = 0;
    vector<string> filters;
    if (const char* filter = getenv("OPENMMRIGID_TEST_FILTER")) {
        std::stringstream parts(filter);
        for (string part; std::getline(parts, part, '|');)
            filters.push_back(part);
    }
    for (auto& test : tests) {
        if (!filters.empty() && std::none_of(filters.begin(), filters.end(),
                                             [&](const string& part) { return test.first.find(part) != string::npos; }))
            continue;
        try {
            auto start = std::chrono::steady_clock::now();
            test.second();
            std::chrono::duration<double> seconds = std::chrono::steady_clock::now() - start;
            std::cout << "ok   " << test.first << " (" << message(seconds.count()) << " s)" << std::endl;
        }
        catch (const std::exception& e) {
            std::cout << "FAIL " << test.first << ": " << e.what() << std::endl;
            failures++;
        }
    }
    return failures;
}

/**
 * The main() of a platform's test file: set the platform up (load it, register our kernels), run
 * the tests of one suite on it (runPlatformTests, runThermostatTests),
 * and report the way ctest and OpenMM's own tests do.
 */
inline int runMain(const std::function<Platform&()>& setUpPlatform, const std::function<int(Platform&)>& runTests) {
    try {
        int failures = runTests(setUpPlatform());
        if (failures > 0) {
            std::cout << failures << " test(s) failed" << std::endl;
            return 1;
        }
    }
    catch (const std::exception& e) {
        std::cout << "exception: " << e.what() << std::endl;
        return 1;
    }
    std::cout << "Done" << std::endl;
    return 0;
}


} // namespace RigidBodyIntegratorTests

#endif
