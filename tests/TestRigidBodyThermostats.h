/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * Tests of constant temperature, shared by every platform: the               *
 * RigidBodyLangevinIntegrator and RigidBodyBussiIntegrator (stochastic      *
 * velocity rescaling). Each platform's Test<Platform>RigidBodyThermostats   *
 * .cpp includes this file and calls runMain() with runThermostatTests.       *
 *                                                                            *
 * Every check compares against something known:                              *
 * - Philox4x32-10 against the known-answer vectors of Random123;            *
 * - Langevin: free bodies of every kind and free atoms (no forces) sample   *
 *   the canonical momenta exactly: the kinetic energy of each kind of       *
 *   degree of freedom has the mean and variance of a Gamma distribution    *
 *   with shape dof/2 and scale kT (5 standard errors), with either rotation *
 *   method;                                                                 *
 * - Langevin, particles in a harmonic trap at omega dt = 1: LFMiddle samples *
 *   positions exactly, <x^2> = kT/k, and the velocities it reports (half a  *
 *   step behind) exactly too, <v^2> = kT/m, where BAOAB's on-step ones     *
 *   read (kT/m)(1 - (omega dt)^2/4) (5 standard errors), for single-       *
 *   particle bodies and free particles alike;                               *
 * - Langevin at T = 0 without forces: the kinetic energy decays exactly as  *
 *   c^(2n);                                                                 *
 * - Langevin with friction 0 is leapfrog Verlet: independent of the seed    *
 *   bit for bit, and the trajectory of RigidBodyIntegrator (Verlet) to      *
 *   rounding, with its velocities half a kick behind Verlet's;              *
 * - thermostat (Bussi): the total kinetic energy of free bodies is Gamma     *
 *   distributed, with the degrees of freedom counted from the System (and   *
 *   computeSystemTemperature() reads them so); at T = 0 it decays as c^n;   *
 *   total energy minus the heat (the thermostat's work) is conserved like   *
 *   the energy of the constant-energy integrator while the heat is large;   *
 *   a constant-energy integrator has no heat; checkpoints of the two load   *
 *   into each other, not into Langevin; each step is eq. (A7) of its kinetic *
 *   energy with the step's deviates, as an independent transcription of the *
 *   formula computes it on the host (bit for bit on Reference, as before    *
 *   the factor moved to the device): the velocities, the heat and the       *
 *   shadow work; a checkpoint load or a new Context drops the work the      *
 *   kernel had not yet handed over;                                         *
 * - both: the same seed gives the same trajectory (bit for bit; on CPU with *
 *   1 or 2 threads), another seed or seed 0 another; a checkpoint continues *
 *   the random sequence (and the thermostat's heat) exactly;                *
 * - constraints among free particles and body shapes hold under the noise;  *
 * - bad temperatures, frictions and collision times raise OpenMMException   *
 *   naming the value, leaving the integrator and its Context usable.        *
 * -------------------------------------------------------------------------- */

#include "RigidBodyTestSystems.h"
#include "numerics/Philox.h"
#include "numerics/StochasticRescaling.h"
#include "openmm/CustomExternalForce.h"
#include "openmm/reference/SimTKOpenMMRealType.h"

namespace RigidBodyIntegratorTests {

// ------------------------------------------------------------------------------------------------
// The random numbers
// ------------------------------------------------------------------------------------------------

void testPhiloxKnownAnswers() {
    // Random123 1.14, tests/kat_vectors: the three "philox4x32 10" lines (counter, key, result).
    struct Vector {
        std::array<uint32_t, 4> counter;
        std::array<uint32_t, 2> key;
        std::array<uint32_t, 4> result;
    };
    const Vector vectors[] = {
        {{0, 0, 0, 0}, {0, 0}, {0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8}},
        {{0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff}, {0xffffffff, 0xffffffff}, {0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd}},
        {{0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344}, {0xa4093822, 0x299f31d0}, {0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1}},
    };
    for (const Vector& v : vectors)
        check(philox4x32(v.counter, v.key) == v.result, message("Philox4x32-10 of counter ", v.counter[0], "...: wrong output"));
    // The normal deviates of one stream: mean 0, variance 1, fourth moment 3 (5 standard errors).
    NormalStream stream(12345, 7, 99);
    const int n = 200000;
    double sum = 0, sum2 = 0, sum4 = 0;
    for (int i = 0; i < n; i++) {
        double x = stream.next();
        sum += x;
        sum2 += x*x;
        sum4 += x*x*x*x;
    }
    check(fabs(sum/n) < 5/sqrt(n), message("normal deviates: mean ", sum/n));
    check(fabs(sum2/n - 1) < 5*sqrt(2.0/n), message("normal deviates: variance ", sum2/n));
    check(fabs(sum4/n - 3) < 5*sqrt(96.0/n), message("normal deviates: fourth moment ", sum4/n));
    // Streams and steps are independent: another stream or step gives other numbers.
    NormalStream same(12345, 7, 99), otherStream(12345, 8, 99), otherStep(12345, 7, 100), otherSeed(12346, 7, 99);
    double first = same.next();
    check(first != otherStream.next() && first != otherStep.next() && first != otherSeed.next(), "streams differ");
}

// ------------------------------------------------------------------------------------------------
// Canonical sampling
// ------------------------------------------------------------------------------------------------

/**
 * Free bodies of every kind and two free atoms, no forces: the free motion conserves the kinetic
 * energy of each body and the Ornstein-Uhlenbeck step leaves the canonical momenta invariant, so
 * every sample of the kinetic energy of n degrees of freedom is Gamma(n/2, kT) distributed, exactly
 * (no step-size error). With friction dt = 0.5 (c = 0.61) samples 4 steps apart correlate by
 * c^8 = 0.02, so they count as independent. Checked by kind: translation (bodies and free atoms),
 * and the rotation of linear, spherical, symmetric and asymmetric bodies; a wrong noise amplitude
 * for any of them (sqrt(I) for I, 1 - c for 1 - c^2, noise along a linear body's axis) shifts the mean.
 * NO_SQUISH's free rotation keeps the kinetic energy too (it is a composition of exact rotations
 * about the principal axes), so the same holds with either rotation method.
 */
void testCanonicalKineticEnergy(Platform& platform, RigidBodyIntegratorBase::RotationMethod method) {
    Scene scene = makeCluster(5, 4, 4, 4, false);
    const double temperature = 300, kT = boltzmann*temperature, dt = 0.002, friction = 0.5/dt;
    LangevinRun run = startLangevin(scene, platform, temperature, friction, dt, 17);
    run.integrator->setRotationMethod(method);
    const vector<string> kinds = {"point", "linear", "spherical", "symmetric", "asymmetric"};
    vector<string> kindOf(scene.bodies.size());
    std::map<string, int> rotationalDof = {{"point", 0}, {"linear", 2}, {"spherical", 3}, {"symmetric", 3}, {"asymmetric", 3}};
    std::map<string, int> dof;
    int translationalDof = 3*(scene.bodies.size() + scene.free.size());
    for (size_t b = 0; b < scene.bodies.size(); b++) {
        kindOf[b] = bodyKind(scene.masses, scene.positions, scene.bodies[b]);
        dof[kindOf[b]] += rotationalDof[kindOf[b]];
    }
    run.integrator->step(20);
    const int samples = 2000, interval = 4;
    vector<double> translational;
    std::map<string, vector<double> > rotational;
    for (int s = 0; s < samples; s++) {
        run.integrator->step(interval);
        vector<Vec3> v = velocitiesOf(*run.context);
        double trans = 0;
        std::map<string, double> rot;
        for (size_t b = 0; b < scene.bodies.size(); b++) {
            Vec3 momentum;
            double mass = 0;
            for (int p : scene.bodies[b]) {
                momentum += v[p]*scene.masses[p];
                mass += scene.masses[p];
            }
            Vec3 centre = momentum/mass;
            trans += 0.5*mass*centre.dot(centre);
            for (int p : scene.bodies[b])
                rot[kindOf[b]] += 0.5*scene.masses[p]*(v[p] - centre).dot(v[p] - centre);
        }
        for (int p : scene.free)
            trans += 0.5*scene.masses[p]*v[p].dot(v[p]);
        translational.push_back(trans);
        for (const string& kind : kinds)
            if (dof[kind] > 0)
                rotational[kind].push_back(rot[kind]);
    }
    auto checkGamma = [&](const string& what, const vector<double>& energies, int n) {
        double mean, meanError, variance, varianceError;
        sampleMoments(energies, mean, meanError, variance, varianceError);
        double expectedMean = 0.5*n*kT, expectedVariance = 0.5*n*kT*kT;
        string report = message(methodName(method), ", ", what, " (", n, " dof): mean ", mean, " +- ", meanError, " kJ/mol (expected ", expectedMean,
                                "), variance ", variance, " +- ", varianceError, " (expected ", expectedVariance, ")");
        std::cout << report << std::endl;
        check(fabs(mean - expectedMean) < 5*meanError, report);
        check(fabs(variance - expectedVariance) < 5*varianceError, report);
    };
    checkGamma("translation", translational, translationalDof);
    for (const string& kind : kinds)
        if (dof[kind] > 0)
            checkGamma("rotation of " + kind + " bodies", rotational[kind], dof[kind]);
}

/**
 * Single-particle bodies and free particles (masses 20 and 40) in isotropic harmonic traps with
 * omega dt = 1 for every particle. For a harmonic oscillator BAOAB samples the positions exactly,
 * <x^2> = kT/k, and the velocities after its closing half kick with <v^2> = (kT/m)(1 - (omega dt)^2/4)
 * (Leimkuhler and Matthews, Appl. Math. Res. Express 2013, 34): 3/4 of kT/m here. Another order of
 * the stages (OBABO, ABOBA) or a half-step O stage would give other values. Samples 10 steps apart;
 * each coordinate of each particle is an independent oscillator.
 */
void testHarmonicTrap(Platform& platform) {
    const double temperature = 300, kT = boltzmann*temperature, dt = 0.004, omega = 1.0/dt, friction = 0.5/dt;
    const int numEach = 50;
    Scene scene;
    CustomExternalForce* trap = new CustomExternalForce("0.5*k*(x*x + y*y + z*z)");
    trap->addPerParticleParameter("k");
    std::mt19937_64 rng(3);
    std::normal_distribution<double> normal;
    for (int i = 0; i < 4*numEach; i++) {
        double mass = (i%2 == 0 ? 20.0 : 40.0), k = mass*omega*omega;
        int p = scene.system->addParticle(mass);
        trap->addParticle(p, {k});
        scene.masses.push_back(mass);
        scene.positions.push_back(Vec3(normal(rng), normal(rng), normal(rng))*sqrt(kT/k));
        scene.velocities.push_back(Vec3(normal(rng), normal(rng), normal(rng))*sqrt(kT/mass));
        if (i < 2*numEach)
            scene.bodies.push_back({p});
        else
            scene.free.push_back(p);
    }
    scene.system->addForce(trap);
    LangevinRun run = startLangevin(scene, platform, temperature, friction, dt, 29);
    run.integrator->step(50);
    std::map<string, vector<double> > positionRatios, velocityRatios;
    for (int s = 0; s < 1500; s++) {
        run.integrator->step(10);
        State state = run.context->getState(State::Positions | State::Velocities);
        const vector<Vec3>& r = state.getPositions();
        const vector<Vec3>& v = state.getVelocities();
        for (size_t p = 0; p < r.size(); p++) {
            string group = (p < 2*(size_t) numEach ? "single-particle bodies" : "free particles");
            double k = scene.masses[p]*omega*omega;
            for (int c = 0; c < 3; c++) {
                positionRatios[group].push_back(k*r[p][c]*r[p][c]/kT);
                velocityRatios[group].push_back(scene.masses[p]*v[p][c]*v[p][c]/kT);
            }
        }
    }
    for (const string& group : {string("single-particle bodies"), string("free particles")}) {
        double mean, error, variance, varianceError;
        sampleMoments(positionRatios[group], mean, error, variance, varianceError);
        string report = message(group, " in a harmonic trap, omega dt = 1: k <x^2>/kT = ", mean, " +- ", error, " (expected 1)");
        std::cout << report << std::endl;
        check(fabs(mean - 1) < 5*error, report);
        sampleMoments(velocityRatios[group], mean, error, variance, varianceError);
        // The reported velocities are those after the Ornstein-Uhlenbeck step and a free drift: exactly
        // canonical. (On-step velocities, half a kick later, would give 1 - (omega dt)^2/4 = 0.75.)
        report = message(group, " in a harmonic trap, omega dt = 1: m <v^2>/kT = ", mean, " +- ", error, " (expected 1)");
        std::cout << report << std::endl;
        check(fabs(mean - 1) < 5*error, report);
    }
}

/**
 * At temperature 0 without forces each step multiplies every momentum by c = exp(-friction dt) and
 * the free motion keeps the kinetic energy: after n steps it is c^(2n) times the first, for bodies
 * of every kind and free atoms (to rounding).
 */
void testDampedAtZeroTemperature(Platform& platform) {
    Scene scene = makeCluster(3, 3, 3, 3, false);
    const double dt = 0.002, friction = 20.0;
    LangevinRun run = startLangevin(scene, platform, 0.0, friction, dt, 1);
    double initial = 0;
    for (size_t i = 0; i < scene.masses.size(); i++)
        initial += 0.5*scene.masses[i]*scene.velocities[i].dot(scene.velocities[i]);
    const int steps = 40;
    run.integrator->step(steps);
    double kinetic = run.context->getState(State::Energy).getKineticEnergy();
    double expected = initial*exp(-2*friction*dt*steps);
    string report = message("T = 0: kinetic energy ", kinetic, " kJ/mol after ", steps, " steps, expected ", expected);
    std::cout << report << std::endl;
    check(fabs(kinetic/expected - 1) < 1e-10, report);
    // The same from the translation and rotation of each body and the free atoms' motion.
    ASSERT_EQUAL_TOL(expected, rigidKineticEnergy(scene.masses, scene.bodies, velocitiesOf(*run.context)), 1e-10);
}

// ------------------------------------------------------------------------------------------------
// Friction 0, seeds, threads, checkpoints
// ------------------------------------------------------------------------------------------------

/**
 * With friction 0 the step is leapfrog Verlet: no random numbers (the seed does not matter, bit for
 * bit), and the positions of RigidBodyIntegrator's Verlet step, whose one exact drift is the
 * composition of the two halves, when it starts from the same state: velocities half a kick behind
 * Verlet's on-step ones (to rounding, amplified by the cluster's chaos over 100 steps). After the
 * steps, Verlet's on-step velocities taken half a kick back, v - (dt/2) F/m projected onto rigid
 * motion (which keeps each body's momentum and angular momentum, so that this is the half kick of
 * its momenta by its force and torque), are the Langevin integrator's velocities.
 */
void testFrictionZero(Platform& platform) {
    Scene scene = makeCluster(7, 3, 3, 2, true);
    const double dt = 0.001;
    const int steps = 100;
    Run verlet = startRigid(scene, platform, dt, RigidBodyIntegrator::Exact);
    // The state Verlet starts from (projected onto rigid motion), half a kick back.
    auto halfKickBack = [&](Context& context) {
        State state = context.getState(State::Positions | State::Velocities | State::Forces);
        vector<Vec3> velocities = state.getVelocities();
        for (size_t i = 0; i < velocities.size(); i++)
            if (scene.masses[i] > 0)
                velocities[i] -= state.getForces()[i]*(0.5*dt/scene.masses[i]);
        return std::make_pair(state.getPositions(), velocities);
    };
    std::pair<vector<Vec3>, vector<Vec3> > start = halfKickBack(*verlet.context);
    Scene shifted = scene;
    shifted.positions = start.first;
    shifted.velocities = start.second;
    LangevinRun first = startLangevin(shifted, platform, 300.0, 0.0, dt, 1), second = startLangevin(shifted, platform, 300.0, 0.0, dt, 2);
    first.integrator->step(steps);
    second.integrator->step(steps);
    verlet.integrator->step(steps);
    vector<Vec3> positions = positionsOf(*first.context);
    check(maxDifference(positions, positionsOf(*second.context)) == 0.0, "friction 0: the seed changes the trajectory");
    double difference = maxDifference(positions, positionsOf(*verlet.context));
    std::pair<vector<Vec3>, vector<Vec3> > end = halfKickBack(*verlet.context);
    verlet.context->setVelocities(end.second);  // projected onto rigid motion at once
    double velocityDifference = maxDifference(first.context->getState(State::Velocities).getVelocities(),
                                              verlet.context->getState(State::Velocities).getVelocities());
    string report = message("friction 0: positions differ from RigidBodyIntegrator's by ", difference,
                            " nm, velocities from its half-kicked ones by ", velocityDifference, " nm/ps");
    std::cout << report << std::endl;
    check(difference < 1e-9, report);
    check(velocityDifference < 1e-9, report);
}

/**
 * What a stochastic integrator's seed must do. runFor(scene, seed, properties, steps) starts one on the
 * scene with that seed and returns the positions after the steps: the same seed gives the same
 * positions, seeds 5 and 6 give positions more than `apart` nm apart, and so do two Contexts with
 * seed 0 (each picks its own). On CPU, from 64 bodies each per-body loop runs on the thread pool at its
 * second run and after that wherever the pool is faster (ThreadedLoopChoice): the
 * trajectory must not depend on the number of threads (no forces, so that only this plugin's
 * arithmetic is compared).
 */
void checkSeeds(Platform& platform, const Scene& scene, double apart, const string& who,
                const std::function<vector<Vec3>(const Scene&, int, const std::map<string, string>&, int)>& runFor) {
    vector<Vec3> a = runFor(scene, 5, platformProperties, 50), b = runFor(scene, 5, platformProperties, 50);
    check(maxDifference(a, b) == 0.0, message(who, "the same seed gave positions ", maxDifference(a, b), " nm apart"));
    double other = maxDifference(a, runFor(scene, 6, platformProperties, 50));
    check(other > apart, message(who, "seeds 5 and 6 gave positions only ", other, " nm apart"));
    double zero = maxDifference(runFor(scene, 0, platformProperties, 50), runFor(scene, 0, platformProperties, 50));
    check(zero > apart, message(who, "two Contexts with seed 0 gave positions only ", zero, " nm apart"));
    if (platform.getName() == "CPU") {
        Scene many = makeCluster(13, 4, 4, 5, false);
        vector<Vec3> byThreads[2];
        for (int k = 0; k < 2; k++) {
            std::map<string, string> properties = platformProperties;
            properties["Threads"] = (k == 0 ? "1" : "2");
            byThreads[k] = runFor(many, 8, properties, 30);
        }
        check(maxDifference(byThreads[0], byThreads[1]) == 0.0, who + "1 and 2 threads gave different trajectories");
    }
}

void testSeeds(Platform& platform) {
    checkSeeds(platform, makeCluster(11, 3, 3, 2, true), 1e-4, "",
               [&](const Scene& scene, int seed, const std::map<string, string>& properties, int steps) {
        LangevinRun run = startLangevin(scene, platform, 300.0, 5.0, 0.002, seed, properties);
        run.integrator->step(steps);
        check(run.integrator->getRandomNumberSeed() == seed, "the seed is kept");
        return positionsOf(*run.context);
    });
}

void testCheckpoint(Platform& platform) {
    Scene scene = makeCluster(11, 3, 3, 2, true);
    LangevinRun run = startLangevin(scene, platform, 300.0, 5.0, 0.002, 3);
    run.integrator->step(20);
    std::stringstream checkpoint;
    run.context->createCheckpoint(checkpoint);
    run.integrator->step(30);
    vector<Vec3> straight = positionsOf(*run.context);
    run.context->loadCheckpoint(checkpoint);
    run.integrator->step(30);
    // After loading, the bodies are re-fitted to the positions (rounding, ~1e-15 nm); a random
    // sequence that did not continue would put them some 1e-3 nm apart.
    double resumed = maxDifference(straight, positionsOf(*run.context));
    check(resumed < 1e-10, message("a checkpoint does not continue the trajectory: ", resumed, " nm apart"));
    // A Context with another seed, loading the checkpoint, continues it too: the seed is in it.
    LangevinRun other = startLangevin(scene, platform, 300.0, 5.0, 0.002, 4);
    checkpoint.clear();
    checkpoint.seekg(0);
    other.context->loadCheckpoint(checkpoint);
    other.integrator->step(30);
    double loaded = maxDifference(straight, positionsOf(*other.context));
    check(loaded < 1e-10, message("a checkpoint loaded into another Context: ", loaded, " nm apart"));
}

// ------------------------------------------------------------------------------------------------
// Constraints, bad input
// ------------------------------------------------------------------------------------------------

/** The mixed system (constrained chain, rigid bodies of every kind, free ion) under noise: rigid bodies, constraints kept. */
void testConstraintsUnderNoise(Platform& platform) {
    std::set<std::pair<int, int> > chainConstraints;
    Scene scene = makeMixed(chainConstraints);
    const double tolerance = 1e-8;
    LangevinRun run = startLangevin(scene, platform, 300.0, 10.0, 0.001, 4);
    run.integrator->setConstraintTolerance(tolerance);
    run.context->applyConstraints(tolerance);
    vector<Vec3> start = positionsOf(*run.context);
    run.integrator->step(300);
    checkRigidAndConstrained(scene, start, positionsOf(*run.context), velocitiesOf(*run.context), tolerance);
}

void testBadTemperatureAndFriction(Platform& platform) {
    const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
    auto expectError = [](const std::function<void()>& action, const string& word, const string& what) {
        try {
            action();
        }
        catch (const OpenMMException& e) {
            check(string(e.what()).find(word) != string::npos, what + ": the message does not name the " + word + ": " + e.what());
            return;
        }
        throw OpenMMException("Assertion failure: " + what + " raised no exception");
    };
    for (double bad : {-1.0, -1e-300, inf, -inf, nan}) {
        expectError([&]() { RigidBodyLangevinIntegrator(bad, 1.0, 0.002); }, "temperature", message("temperature ", bad));
        expectError([&]() { RigidBodyLangevinIntegrator(300.0, bad, 0.002, {{0}}); }, "friction", message("friction ", bad));
    }
    std::unique_ptr<System> system(smallSystem());
    RigidBodyLangevinIntegrator integrator(300.0, 2.0, 0.002, {{0, 1, 2}, {3, 4}});
    integrator.setRandomNumberSeed(9);
    Context context(*system, integrator, platform, platformProperties);
    context.setPositions(smallPositions);
    integrator.step(5);
    for (double bad : {-5.0, inf, nan}) {
        expectError([&]() { integrator.setTemperature(bad); }, "temperature", message("setTemperature(", bad, ")"));
        expectError([&]() { integrator.setFriction(bad); }, "friction", message("setFriction(", bad, ")"));
    }
    check(integrator.getTemperature() == 300.0 && integrator.getFriction() == 2.0, "bad values leave the settings unchanged");
    integrator.step(5);
    for (const Vec3& r : positionsOf(context))
        check(std::isfinite(r.dot(r)), "the Context works after bad values");
    integrator.setTemperature(0.0);
    integrator.setFriction(0.0);
    integrator.step(2);
}

// ------------------------------------------------------------------------------------------------
// RigidBodyIntegrator's thermostat (stochastic velocity rescaling)
// ------------------------------------------------------------------------------------------------

/**
 * Free bodies of every kind and two free atoms, no forces: the free motion keeps the kinetic energy
 * and the rescaling samples it from the canonical distribution of N_f degrees of freedom (counted
 * from the System: 3 per free atom, 3 + 0, 2 or 3 per body by its kind), Gamma(N_f/2, kT), exactly;
 * computeSystemTemperature() reads 2 K / (N_f k_B) with the same N_f. (Without forces nothing exchanges energy between
 * the bodies, so only the total is canonical.) dt/tau = 0.5; samples 6 steps apart correlate by
 * exp(-3) = 0.05.
 */
void testThermostatCanonicalKineticEnergy(Platform& platform) {
    Scene scene = makeCluster(5, 4, 4, 4, false);
    const double temperature = 300, kT = boltzmann*temperature, dt = 0.002;
    BussiRun run = startThermostat(scene, platform, temperature, 2*dt, dt, 31);
    const int dof = countDegreesOfFreedom(*scene.system, scene.bodies, scene.positions);
    run.integrator->step(20);
    const double kinetic = run.context->getState(State::Energy).getKineticEnergy();
    const double reported = run.integrator->computeSystemTemperature(), counted = 2*kinetic/(dof*BOLTZ);
    check(fabs(reported - counted) <= 1e-12*counted, message("thermostat: computeSystemTemperature() ", reported, " K, 2 K / (N_f k_B) ",
                                                             counted, " K with the ", dof, " degrees of freedom counted"));
    vector<double> energies;
    for (int s = 0; s < 2000; s++) {
        run.integrator->step(6);
        energies.push_back(run.context->getState(State::Energy).getKineticEnergy());
    }
    double mean, meanError, variance, varianceError;
    sampleMoments(energies, mean, meanError, variance, varianceError);
    double expectedMean = 0.5*dof*kT, expectedVariance = 0.5*dof*kT*kT;
    string report = message("thermostat, free bodies (", dof, " dof): kinetic energy ", mean, " +- ", meanError,
                            " kJ/mol (expected ", expectedMean, "), variance ", variance, " +- ", varianceError, " (expected ",
                            expectedVariance, ")");
    std::cout << report << std::endl;
    check(fabs(mean - expectedMean) < 5*meanError, report);
    check(fabs(variance - expectedVariance) < 5*varianceError, report);
}

/**
 * The kinetic energy alone, iterated through eq. (A7) with c = 0.5: its stationary distribution is
 * Gamma(N_f/2, kT) (mean N_f kT/2, variance N_f (kT)^2/2), for N_f = 3 (chi-squared deviates as sums
 * of squares) and N_f = 200 (Marsaglia-Tsang). Successive values correlate by c, so the standard
 * errors are those of independent samples times sqrt((1 + c)/(1 - c)) (and for the variance the
 * square of that factor, (1 + c^2)/(1 - c^2), is used, slightly generous).
 */
void testStochasticRescalingRecurrence() {
    const double kT = 2.5, c = 0.5;
    for (int dof : {3, 200}) {
        NormalStream random(77, dof, 0);
        double kinetic = 0.5*dof*kT, newKinetic;
        vector<double> samples;
        for (int i = 0; i < 200000; i++) {
            stochasticRescalingFactor(kinetic, 0.5*dof*kT, dof, c, random, newKinetic);
            kinetic = newKinetic;
            samples.push_back(kinetic);
        }
        double mean, meanError, variance, varianceError;
        sampleMoments(samples, mean, meanError, variance, varianceError);
        meanError *= sqrt((1 + c)/(1 - c));
        varianceError *= sqrt((1 + c*c)/(1 - c*c))*sqrt((1 + c)/(1 - c));
        string report = message("eq. (A7) iterated, ", dof, " dof: mean ", mean, " +- ", meanError, " (expected ", 0.5*dof*kT,
                                "), variance ", variance, " +- ", varianceError, " (expected ", 0.5*dof*kT*kT, ")");
        std::cout << report << std::endl;
        check(fabs(mean - 0.5*dof*kT) < 5*meanError, report);
        check(fabs(variance - 0.5*dof*kT*kT) < 5*varianceError, report);
    }
    // The chi-squared deviates themselves: mean n, variance 2n.
    for (int n : {7, 32, 33, 150}) {
        NormalStream random(5, n, 1);
        vector<double> samples;
        for (int i = 0; i < 100000; i++)
            samples.push_back(chiSquaredDeviate(n, random));
        double mean, meanError, variance, varianceError;
        sampleMoments(samples, mean, meanError, variance, varianceError);
        string report = message("chi-squared deviates, n = ", n, ": mean ", mean, " +- ", meanError, ", variance ", variance,
                                " +- ", varianceError);
        check(fabs(mean - n) < 5*meanError && fabs(variance - 2*n) < 5*varianceError, report);
    }
}

/** At temperature 0 every step scales the kinetic energy by c = exp(-dt/tau) exactly (no forces). */
void testThermostatDampsAtZeroTemperature(Platform& platform) {
    Scene scene = makeCluster(3, 3, 3, 3, false);
    const double dt = 0.002, tau = 0.05;
    BussiRun run = startThermostat(scene, platform, 0.0, tau, dt, 1, platformProperties, true);
    double initial = 0;
    for (size_t i = 0; i < scene.masses.size(); i++)
        initial += 0.5*scene.masses[i]*scene.velocities[i].dot(scene.velocities[i]);
    const int steps = 40;
    run.integrator->step(steps);
    double kinetic = run.context->getState(State::Energy).getKineticEnergy(), expected = initial*exp(-steps*dt/tau);
    check(fabs(kinetic/expected - 1) < 1e-10, message("thermostat at T = 0: kinetic energy ", kinetic, ", expected ", expected));
    ASSERT_EQUAL_TOL(expected - initial, run.integrator->getHeat(), 1e-10);
}

/**
 * Bussi's effective energy, total energy minus the heat (the thermostat's work, getHeat()), is
 * conserved as the energy is by the constant-energy integrator: the interacting cluster starts at
 * 300 K and is thermostatted at 150 K with tau = 0.02 ps, so the work is large (many times the energy error), and the largest
 * |H~ - H~(0)| over 0.2 ps at 1 fs stays within twice the energy error of RigidBodyIntegrator
 * without a thermostat from the same start (Verlet; measured 0.3 times, the cooled cluster moving
 * more slowly) and falls by about 4 (second order: 3 to 5) at 0.5 fs.
 */
void testThermostatEffectiveEnergy(Platform& platform) {
    Scene scene = makeCluster(7, 3, 3, 2, true);
    double deviations[2], work = 0;
    for (int k = 0; k < 2; k++) {
        const double dt = 0.001/(1 << k);
        BussiRun run = startThermostat(scene, platform, 150.0, 0.02, dt, 5, platformProperties, true);
        const int steps = (int) round(0.2/dt);
        vector<double> effective;
        for (int i = 0; i <= steps; i += steps/40) {
            if (i > 0)
                run.integrator->step(steps/40);
            effective.push_back(totalEnergy(*run.context) - run.integrator->getHeat());
        }
        deviations[k] = maxDeviation(effective);
        work = run.integrator->getHeat();
    }
    Run verlet = startRigid(scene, platform, 0.001, RigidBodyIntegrator::Exact);
    vector<double> times, energies;
    recordEnergies(*verlet.context, *verlet.integrator, 200, 5, times, energies);
    double verletDeviation = maxDeviation(energies), ratio = deviations[0]/deviations[1];
    string report = message("thermostat: max |H~ - H~(0)| ", deviations[0], " kJ/mol at 1 fs, ", deviations[1],
                            " at 0.5 fs (ratio ", ratio, "); work ", work, " kJ/mol; constant energy at 1 fs: ", verletDeviation);
    std::cout << report << std::endl;
    check(fabs(work) > 100*deviations[0], report);
    check(deviations[0] < 2*verletDeviation, report);
    check(ratio > 3 && ratio < 5, report);
}

/**
 * The settings of RigidBodyBussiIntegrator: a constant-energy RigidBodyIntegrator has no heat; seeds
 * and threads; a checkpoint continues the random numbers and keeps the heat; checkpoints of
 * RigidBodyIntegrator and RigidBodyBussiIntegrator load into each other (one format), not into a
 * RigidBodyLangevinIntegrator; bad temperatures and collision times raise an exception naming them.
 */
void testThermostatSettings(Platform& platform) {
    Scene scene = makeCluster(11, 3, 3, 2, true);
    // Constant energy: the heat of the steps is exactly 0.
    Run plain = startRigid(scene, platform, 0.002, RigidBodyIntegrator::Exact);
    plain.integrator->setMeasureShadowWork(true);
    plain.integrator->step(30);
    check(maxDifference(positionsOf(*plain.context), scene.positions) > 1e-3, "the constant-energy run moved");
    check(plain.integrator->getHeat() == 0.0, message("constant energy: heat ", plain.integrator->getHeat(), " kJ/mol"));
    // Seeds.
    checkSeeds(platform, scene, 1e-6, "thermostat: ",
               [&](const Scene& body, int seed, const std::map<string, string>& properties, int steps) {
        BussiRun run = startThermostat(body, platform, 300.0, 0.01, 0.002, seed, properties);
        run.integrator->step(steps);
        check(run.integrator->getRandomNumberSeed() == seed, "thermostat: the seed is kept");
        return positionsOf(*run.context);
    });
    // A checkpoint continues the random numbers and keeps the heat.
    BussiRun run = startThermostat(scene, platform, 200.0, 0.01, 0.002, 3, platformProperties, true);
    run.integrator->step(20);
    std::stringstream checkpoint;
    run.context->createCheckpoint(checkpoint);
    double work = run.integrator->getHeat();
    run.integrator->step(30);
    vector<Vec3> straight = positionsOf(*run.context);
    double straightWork = run.integrator->getHeat();
    BussiRun other = startThermostat(scene, platform, 200.0, 0.01, 0.002, 4, platformProperties, true);
    other.context->loadCheckpoint(checkpoint);
    ASSERT_EQUAL_TOL(work, other.integrator->getHeat(), 1e-15);
    other.integrator->step(30);
    double resumed = maxDifference(straight, positionsOf(*other.context));
    check(resumed < 1e-10, message("thermostat: a checkpoint does not continue the trajectory: ", resumed, " nm apart"));
    ASSERT_EQUAL_TOL(straightWork, other.integrator->getHeat(), 1e-9);
    // The thermostat's checkpoint loads into a constant-energy integrator, which continues from its
    // state without heat, and the constant-energy one's into the thermostat's; neither into Langevin.
    checkpoint.clear();
    checkpoint.seekg(0);
    Run constant = startRigid(scene, platform, 0.002, RigidBodyIntegrator::Exact);
    constant.integrator->setMeasureShadowWork(true);
    constant.context->loadCheckpoint(checkpoint);
    const vector<Vec3> saved = positionsOf(*constant.context);
    check(maxDifference(saved, scene.positions) > 1e-3, "the checkpoint holds the state after 20 steps");
    constant.integrator->step(10);
    check(maxDifference(positionsOf(*constant.context), saved) > 1e-4, "the constant-energy integrator moves on from the checkpoint");
    const double constantHeat = constant.integrator->getHeat();
    ASSERT_EQUAL_TOL(work, constantHeat, 1e-15);  // the checkpoint's heat, and none since
    std::stringstream constantCheckpoint;
    constant.context->createCheckpoint(constantCheckpoint);
    BussiRun back = startThermostat(scene, platform, 200.0, 0.01, 0.002, 4, platformProperties, true);
    back.context->loadCheckpoint(constantCheckpoint);
    check(maxDifference(positionsOf(*back.context), positionsOf(*constant.context)) < 1e-12,
          "a constant-energy checkpoint loads into the thermostat's integrator");
    ASSERT_EQUAL_TOL(constantHeat, back.integrator->getHeat(), 1e-15);
    for (std::stringstream* stream : {&checkpoint, &constantCheckpoint}) {
        stream->clear();
        stream->seekg(0);
        LangevinRun langevin = startLangevin(scene, platform, 200.0, 1.0, 0.002, 5);
        bool refused = false;
        try {
            langevin.context->loadCheckpoint(*stream);
        }
        catch (const OpenMMException& e) {
            refused = string(e.what()).find("RigidBodyLangevinIntegrator") != string::npos &&
                      string(e.what()).find(stream == &checkpoint ? "RigidBodyBussiIntegrator" : "RigidBodyIntegrator") != string::npos;
            check(refused, string("a Langevin integrator refuses the checkpoint, naming both classes: ") + e.what());
        }
        check(refused, "a RigidBodyLangevinIntegrator loaded the checkpoint of another class");
    }
    // Bad values, given to the constructor or set: an exception naming them, the settings unchanged,
    // the Context usable.
    const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
    auto expectError = [](const std::function<void()>& action, const string& word, const string& what) {
        try {
            action();
        }
        catch (const OpenMMException& e) {
            check(string(e.what()).find("RigidBodyBussiIntegrator") != string::npos && string(e.what()).find(word) != string::npos,
                  what + ": the message does not name the class and the " + word + ": " + e.what());
            return;
        }
        throw OpenMMException("Assertion failure: " + what + " raised no exception");
    };
    for (double bad : {-1.0, nan, inf}) {
        expectError([&]() { RigidBodyBussiIntegrator(bad, 0.1, 0.002); }, "temperature", message("temperature ", bad));
        expectError([&]() { run.integrator->setTemperature(bad); }, "temperature", message("setTemperature(", bad, ")"));
    }
    for (double bad : {0.0, -0.1, nan, inf}) {
        expectError([&]() { RigidBodyBussiIntegrator(300.0, bad, 0.002, scene.bodies); }, "collision time",
                    message("collision time ", bad));
        expectError([&]() { run.integrator->setCollisionTime(bad); }, "collision time", message("setCollisionTime(", bad, ")"));
    }
    check(run.integrator->getTemperature() == 200.0 && run.integrator->getCollisionTime() == 0.01,
          "bad thermostat values leave the settings unchanged");
    run.integrator->step(5);
    for (const Vec3& r : positionsOf(*run.context))
        check(std::isfinite(r.dot(r)), "the Context works after bad thermostat values");
}


/**
 * Eqs. (A7) and (A8) of Bussi, Donadio and Parrinello (2007) for one step of the thermostat, written
 * out here as RigidBodyIntegrator's thermostat computed them on the host before the factor moved to the numerics
 * core (an evaluation independent of rigidStochasticRescaling): the deviates R_1, then S (chi-squared
 * with N_f - 1 degrees of freedom), from the step's stream, the new kinetic energy and the signed
 * factor. For K > 0, Kbar > 0 and c < 1.
 */
double transcribedBussiFactor(double kinetic, double targetKinetic, int dof, double c, NormalStream& random, double& newKinetic) {
    const double r1 = random.next(), rest = chiSquaredDeviate(dof - 1, random);
    newKinetic = c*kinetic + (1.0 - c)*targetKinetic*(r1*r1 + rest)/dof + 2.0*r1*std::sqrt(c*(1.0 - c)*kinetic*targetKinetic/dof);
    double alpha = std::sqrt(newKinetic/kinetic);
    if (r1 + std::sqrt(c*dof*kinetic/((1.0 - c)*targetKinetic)) < 0.0)
        alpha = -alpha;
    return alpha;
}

/** The kinetic energy the thermostat aims at and c = exp(-dt/tau), as the step sequence forms them. */
void thermostatParameters(const RigidBodyBussiIntegrator& integrator, int dof, double& targetKinetic, double& c) {
    targetKinetic = 0.5*dof*BOLTZ*integrator.getTemperature();
    c = exp(-integrator.getStepSize()/integrator.getCollisionTime());
}

/** |a - alpha b| over the largest |alpha b| of the components. */
double scaledDifference(const vector<Vec3>& a, double alpha, const vector<Vec3>& b) {
    double worst = 0.0, largest = 0.0;
    for (size_t i = 0; i < a.size(); i++)
        for (int k = 0; k < 3; k++) {
            worst = std::max(worst, fabs(a[i][k] - alpha*b[i][k]));
            largest = std::max(largest, fabs(alpha*b[i][k]));
        }
    return worst/largest;
}

/**
 * A run of the thermostat is eq. (A7) step after step. Free atoms without forces keep their
 * velocities through a step's kicks and drifts, so the kinetic energy each step rescales is the one
 * read after the step before (rigidKineticEnergy(): the sum the kernel forms, in its order), and its
 * velocities must be the previous ones times the factor transcribedBussiFactor() computes from it
 * with the step's deviates (stream 0 of the seed, counter n at step n) and the degrees of freedom
 * counted from the System; the heat (the thermostat's work), read once at the end, is the sum of
 * K' - K. On Reference bit for bit (the values of the host computation this plugin had before the
 * factor moved to the device); elsewhere to rounding (the factor computed on the device, 1e-13).
 * Then the heat counts only the steps that measured it.
 */
void testThermostatStepsFollowEquationA7(Platform& platform) {
    System system;
    vector<Vec3> positions, velocities;
    std::mt19937_64 rng(17);
    std::normal_distribution<double> normal;
    for (int i = 0; i < 12; i++) {
        const double mass = 10.0 + 30.0*(i%3);
        system.addParticle(mass);
        positions.push_back(Vec3(i%3, (i/3)%2, i/6)*0.6);
        velocities.push_back(Vec3(normal(rng), normal(rng), normal(rng))*sqrt(boltzmann*300.0/mass));
    }
    const vector<vector<int> > noBodies;
    RigidBodyBussiIntegrator integrator(250.0, 0.01, 0.002, noBodies);  // no bodies, explicitly
    integrator.setRandomNumberSeed(29);
    integrator.setMeasureShadowWork(true);
    Context context(system, integrator, platform, platformProperties);
    context.setPositions(positions);
    context.setVelocities(velocities);
    vector<double> masses;
    for (int i = 0; i < system.getNumParticles(); i++)
        masses.push_back(system.getParticleMass(i));
    const int dof = countDegreesOfFreedom(system, noBodies, positions);
    double target, c;
    thermostatParameters(integrator, dof, target, c);
    const bool exact = (platform.getName() == "Reference");
    vector<Vec3> before = velocitiesOf(context);
    double work = 0.0, worst = 0.0;
    for (int n = 0; n < 40; n++) {
        const double kinetic = rigidKineticEnergy(masses, noBodies, before);
        NormalStream random(29, 0, n);
        double newKinetic;
        const double alpha = transcribedBussiFactor(kinetic, target, dof, c, random, newKinetic);
        work += newKinetic - kinetic;
        integrator.step(1);
        const vector<Vec3> after = velocitiesOf(context);
        const double difference = scaledDifference(after, alpha, before);
        worst = std::max(worst, difference);
        check(exact ? difference == 0.0 : difference < 1e-13,
              message("thermostat, step ", n, ": velocities ", difference, " (relative) from alpha = ", alpha, " times the last"));
        before = after;
    }
    const double heat = integrator.getHeat();
    string report = message("thermostat: 40 steps of eq. (A7): velocities within ", worst, " (relative), heat ", heat,
                            " kJ/mol (transcription ", work, ")");
    std::cout << report << std::endl;
    check(exact ? heat == work : fabs(heat - work) < 1e-12*fabs(work), report);
    check(fabs(work) > 1.0, report);  // the run does exchange energy with the bath
    // The heat is the work of the steps that measured it: 10 steps without, 10 with. Each part of
    // the work is summed from 0 by the kernel and added when the host takes it (at the switch and
    // at the read).
    integrator.setMeasureShadowWork(false);
    double parts[2] = {0.0, 0.0};
    for (int n = 40; n < 60; n++) {
        if (n == 50)
            integrator.setMeasureShadowWork(true);
        const double kinetic = rigidKineticEnergy(masses, noBodies, velocitiesOf(context));
        NormalStream random(29, 0, n);
        double newKinetic;
        transcribedBussiFactor(kinetic, target, dof, c, random, newKinetic);
        parts[n < 50 ? 0 : 1] += newKinetic - kinetic;
        integrator.step(1);
    }
    const double lastHeat = integrator.getHeat();
    const double expectedHeat = heat + parts[1];
    report = message("thermostat: heat ", lastHeat, " kJ/mol (expected ", expectedHeat, ", without the ", parts[0],
                     " of the steps not measured) after 10 steps without and 10 with the heat measured");
    check(exact ? lastHeat == expectedHeat : fabs(lastHeat - expectedHeat) < 1e-12*fabs(work), report);
    check(fabs(parts[0]) > 1e-3 && fabs(parts[1]) > 1e-3, report);
}

/**
 * One step of bodies with forces: two Contexts start from the same state, one with the thermostat,
 * one without; their step is the same up to the rescaling, so the thermostat's positions must be the
 * other's and its velocities the other's times the factor transcribedBussiFactor() computes from the
 * other's kinetic energy (the same sum, translation plus rotation, of the same velocities:
 * rigidKineticEnergy()) with the deviates of counter 0 and the degrees of freedom counted from the
 * System; its heat (the thermostat's work) is K' - K, and its shadow work (which leaves the
 * rescaling out) the other's. States along a thermostatted run of the interacting cluster. Bit for
 * bit on Reference; elsewhere to rounding.
 */
void testThermostatStepWithBodies(Platform& platform) {
    Scene scene = makeCluster(7, 3, 3, 2, true);
    BussiRun run = startThermostat(scene, platform, 200.0, 0.02, 0.002, 5);
    const bool exact = (platform.getName() == "Reference");
    double worst = 0.0;
    for (int sample = 0; sample < 3; sample++) {
        run.integrator->step(15);
        Scene state = scene;
        state.positions = positionsOf(*run.context);
        state.velocities = velocitiesOf(*run.context);
        BussiRun thermostat = startThermostat(state, platform, 200.0, 0.02, 0.002, 11, platformProperties, true);
        Run plain = startRigid(state, platform, 0.002, RigidBodyIntegrator::Exact);
        plain.integrator->setMeasureShadowWork(true);
        thermostat.integrator->step(1);
        plain.integrator->step(1);
        const int dof = countDegreesOfFreedom(*scene.system, scene.bodies, state.positions);
        double target, c, newKinetic;
        thermostatParameters(*thermostat.integrator, dof, target, c);
        const double kinetic = rigidKineticEnergy(scene.masses, scene.bodies, velocitiesOf(*plain.context));
        NormalStream random(11, 0, 0);
        const double alpha = transcribedBussiFactor(kinetic, target, dof, c, random, newKinetic);
        const double moved = maxDifference(positionsOf(*thermostat.context), positionsOf(*plain.context));
        const double scaled = scaledDifference(velocitiesOf(*thermostat.context), alpha, velocitiesOf(*plain.context));
        const double heat = thermostat.integrator->getHeat();
        const double shadow = thermostat.integrator->getShadowWork(), plainShadow = plain.integrator->getShadowWork();
        worst = std::max(worst, scaled);
        string report = message("thermostat, one step with bodies (sample ", sample, "): alpha ", alpha, ", positions ", moved,
                                " nm apart, velocities ", scaled, " (relative), heat ", heat, " (transcription ", newKinetic - kinetic,
                                "), shadow work ", shadow, " (without the thermostat ", plainShadow, ")");
        if (exact)
            check(moved == 0.0 && scaled == 0.0 && heat == newKinetic - kinetic && shadow == plainShadow, report);
        else
            check(moved < 1e-12 && scaled < 1e-12 && fabs(heat - (newKinetic - kinetic)) < 1e-10*fabs(kinetic) &&
                  fabs(shadow - plainShadow) < 1e-10*fabs(kinetic), report);
        check(fabs(alpha - 1.0) > 1e-3, report);  // a rescaling that would show
    }
    std::cout << "thermostat: one step with bodies is eq. (A7) of its kinetic energy, velocities within " << worst << std::endl;
}

/**
 * The work the kernel accumulates between reads belongs to the state it was done in: a checkpoint
 * saves it (createCheckpoint takes it from the kernel), loading a checkpoint replaces it (the steps
 * taken since the save must not leak in), Context::reinitialize(true) keeps it and
 * reinitialize(false) starts again from 0. The work is read as the heat (measured from the first
 * step, which leaves the work on the kernel until it is read). A twin Context with the same seed
 * reads the work at the same steps.
 */
void testThermostatPendingWork(Platform& platform) {
    Scene scene = makeCluster(11, 3, 3, 2, true);
    BussiRun run = startThermostat(scene, platform, 200.0, 0.01, 0.002, 3, platformProperties, true);
    BussiRun twin = startThermostat(scene, platform, 200.0, 0.01, 0.002, 3, platformProperties, true);
    run.integrator->step(20);
    twin.integrator->step(20);
    std::stringstream checkpoint;
    run.context->createCheckpoint(checkpoint);
    const double saved = twin.integrator->getHeat();
    // Work done after the save, never read, then the checkpoint loaded: exactly the saved work.
    run.integrator->step(30);
    twin.integrator->step(30);
    run.context->loadCheckpoint(checkpoint);
    const double loaded = run.integrator->getHeat(), later = twin.integrator->getHeat();
    string report = message("thermostat: work ", saved, " kJ/mol at the checkpoint, ", later, " 30 steps later, ", loaded,
                            " after loading the checkpoint");
    check(loaded == saved, report);
    check(fabs(later - saved) > 1.0, report);  // the steps after the save did work
    // The loaded run continues the twin's (to the rounding of the re-fit bodies), the work included.
    run.integrator->step(30);
    const double continued = run.integrator->getHeat();
    check(fabs(continued - later) < 1e-9*fabs(later), message("thermostat: work ", continued, " after the load, ", later, " straight on"));
    // Work not yet read survives reinitialize(true), and reinitialize(false) drops it.
    run.integrator->step(10);
    twin.integrator->step(10);
    run.context->reinitialize(true);
    const double kept = run.integrator->getHeat(), straight = twin.integrator->getHeat();
    check(fabs(kept - straight) < 1e-9*fabs(straight) && fabs(kept - continued) > 1.0,
          message("thermostat: work ", kept, " after reinitialize(true), ", straight, " straight on, ", continued, " 10 steps before"));
    run.integrator->step(10);
    run.context->reinitialize(false);
    check(run.integrator->getHeat() == 0.0, "thermostat: work left after reinitialize(false)");
}

// ------------------------------------------------------------------------------------------------

/** Run every constant-temperature test on platform; print each failure and return the number of failures. */
int runThermostatTests(Platform& platform) {
    vector<std::pair<string, std::function<void()> > > tests = {
        {"Philox4x32-10 known answers and normal deviates", []() { testPhiloxKnownAnswers(); }},
        {"canonical kinetic energy of free bodies (Exact)", [&]() { testCanonicalKineticEnergy(platform, RigidBodyIntegratorBase::Exact); }},
        {"canonical kinetic energy of free bodies (NoSquish)", [&]() { testCanonicalKineticEnergy(platform, RigidBodyIntegratorBase::NoSquish); }},
        {"harmonic trap: LFMiddle positions and velocities", [&]() { testHarmonicTrap(platform); }},
        {"damped at zero temperature", [&]() { testDampedAtZeroTemperature(platform); }},
        {"friction 0 is leapfrog Verlet", [&]() { testFrictionZero(platform); }},
        {"seeds and threads", [&]() { testSeeds(platform); }},
        {"checkpoint continues the random numbers", [&]() { testCheckpoint(platform); }},
        {"constraints and rigidity under noise", [&]() { testConstraintsUnderNoise(platform); }},
        {"bad temperature and friction", [&]() { testBadTemperatureAndFriction(platform); }},
        {"thermostat: eq. (A7) and chi-squared deviates", []() { testStochasticRescalingRecurrence(); }},
        {"thermostat: canonical kinetic energy of free bodies", [&]() { testThermostatCanonicalKineticEnergy(platform); }},
        {"thermostat: damped at zero temperature", [&]() { testThermostatDampsAtZeroTemperature(platform); }},
        {"thermostat: effective energy conserved", [&]() { testThermostatEffectiveEnergy(platform); }},
        {"thermostat: no heat at constant energy, seeds, threads, checkpoints, bad values", [&]() { testThermostatSettings(platform); }},
        {"thermostat: steps of free atoms follow eq. (A7)", [&]() { testThermostatStepsFollowEquationA7(platform); }},
        {"thermostat: a step with bodies is eq. (A7) of its kinetic energy", [&]() { testThermostatStepWithBodies(platform); }},
        {"thermostat: pending work, checkpoints and reinitialize", [&]() { testThermostatPendingWork(platform); }},
    };
    return runTestList(tests);
}

} // namespace RigidBodyIntegratorTests
