/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * XML serialization of RigidBodyIntegrator and RigidBodyLangevinIntegrator   *
 * (serialization/), on the Reference platform:                               *
 * - a round trip through XmlSerializer keeps every setting, each one set     *
 *   away from its default, and the class;                                    *
 * - the copy moves as the original does, bit for bit: from the same state    *
 *   (the stochastic ones too, with the same seed), and from a State read     *
 *   mid-run, itself serialized;                                              *
 * - files of earlier versions read with the defaults of what they lack;     *
 *   unknown versions and bad values are an OpenMMException that says so.    *
 * -------------------------------------------------------------------------- */

#include "RigidBodyTestSystems.h"
#include "openmm/serialization/XmlSerializer.h"

namespace RigidBodyIntegratorTests {

using namespace OpenMM;
using namespace OpenMMRigid;
using std::string;
using std::vector;

/** The integrator after a round trip through XML, as the type it must have. */
template <class T>
std::unique_ptr<T> roundTrip(const Integrator& integrator) {
    std::stringstream xml;
    XmlSerializer::serialize<Integrator>(&integrator, "Integrator", xml);
    std::unique_ptr<Integrator> copy(XmlSerializer::deserialize<Integrator>(xml));
    T* typed = dynamic_cast<T*>(copy.get());
    check(typed != nullptr, "the copy has the original's class");
    copy.release();
    return std::unique_ptr<T>(typed);
}

template <class T>
std::unique_ptr<T> fromXml(const string& text) {
    std::stringstream xml(text);
    std::unique_ptr<Integrator> copy(XmlSerializer::deserialize<Integrator>(xml));
    T* typed = dynamic_cast<T*>(copy.get());
    check(typed != nullptr, "the XML gives the class it names");
    copy.release();
    return std::unique_ptr<T>(typed);
}

void checkBaseSettings(const RigidBodyIntegratorBase& copy, const RigidBodyIntegratorBase& original) {
    ASSERT_EQUAL(original.getStepSize(), copy.getStepSize());
    ASSERT_EQUAL(original.getConstraintTolerance(), copy.getConstraintTolerance());
    ASSERT_EQUAL(original.getIntegrationForceGroups(), copy.getIntegrationForceGroups());
    ASSERT_EQUAL(original.getRotationMethod(), copy.getRotationMethod());
    ASSERT_EQUAL(original.getMinimumMomentOfInertia(), copy.getMinimumMomentOfInertia());
    ASSERT_EQUAL(original.hasExplicitBodies(), copy.hasExplicitBodies());
    check(original.getExplicitBodies() == copy.getExplicitBodies(), "the explicit bodies survive the round trip");
    ASSERT_EQUAL(original.getMeasureShadowWork(), copy.getMeasureShadowWork());
    ASSERT_EQUAL(original.getMeasureHeat(), copy.getMeasureHeat());
    ASSERT_EQUAL(original.getAccuracyCheck(), copy.getAccuracyCheck());
}

void checkSettings(const RigidBodyIntegrator& copy, const RigidBodyIntegrator& original) {
    checkBaseSettings(copy, original);
    ASSERT_EQUAL(original.getSplitting(), copy.getSplitting());
    ASSERT_EQUAL(original.getNumForceEvaluations(), copy.getNumForceEvaluations());
    ASSERT_EQUAL(original.hasThermostat(), copy.hasThermostat());
    // The file keeps a removed thermostat's temperature and collision time, but the integrator reads
    // them only with a thermostat on (there is no setter for them alone).
    if (original.hasThermostat()) {
        ASSERT_EQUAL(original.getThermostatTemperature(), copy.getThermostatTemperature());
        ASSERT_EQUAL(original.getThermostatCollisionTime(), copy.getThermostatCollisionTime());
    }
    ASSERT_EQUAL(original.getRandomNumberSeed(), copy.getRandomNumberSeed());
}

void checkSettings(const RigidBodyLangevinIntegrator& copy, const RigidBodyLangevinIntegrator& original) {
    checkBaseSettings(copy, original);
    ASSERT_EQUAL(original.getTemperature(), copy.getTemperature());
    ASSERT_EQUAL(original.getFriction(), copy.getFriction());
    ASSERT_EQUAL(original.getRandomNumberSeed(), copy.getRandomNumberSeed());
}

const vector<vector<int> > someBodies = {{0, 1, 2}, {5}, {3, 4}};

/** Every setting of RigidBodyIntegrator away from its default, in every combination that differs. */
void testIntegratorSettings() {
    RigidBodyIntegrator defaults(0.002);
    for (RigidBodyIntegrator::Splitting splitting : allSplittings) {
        for (bool thermostat : {false, true}) {
            RigidBodyIntegrator original(0.0015, someBodies);
            original.setConstraintTolerance(3e-7);
            original.setIntegrationForceGroups(37);
            original.setRotationMethod(RigidBodyIntegrator::NoSquish);
            original.setMinimumMomentOfInertia(0.0375);
            original.setSplitting(splitting);
            if (thermostat)
                original.setThermostat(251.5, 0.07);
            original.setRandomNumberSeed(12345);
            original.setMeasureShadowWork(true);
            original.setMeasureHeat(thermostat);
            original.setAccuracyCheck(false);
            check(original.getConstraintTolerance() != defaults.getConstraintTolerance() &&
                  original.getIntegrationForceGroups() != defaults.getIntegrationForceGroups() &&
                  original.getMinimumMomentOfInertia() != defaults.getMinimumMomentOfInertia() &&
                  original.getRandomNumberSeed() != defaults.getRandomNumberSeed(), "the settings differ from the defaults");
            checkSettings(*roundTrip<RigidBodyIntegrator>(original), original);
        }
    }
    // A removed thermostat stays removed; bodies found in the System (no list) and
    // an explicit empty list (every particle free) are different settings.
    RigidBodyIntegrator removed(0.002);
    removed.setThermostat(320.0, 0.5);
    removed.removeThermostat();
    checkSettings(*roundTrip<RigidBodyIntegrator>(removed), removed);
    RigidBodyIntegrator empty(0.002, vector<vector<int> >());
    std::unique_ptr<RigidBodyIntegrator> emptyCopy = roundTrip<RigidBodyIntegrator>(empty);
    check(emptyCopy->hasExplicitBodies() && emptyCopy->getExplicitBodies().empty(), "an explicit empty list of bodies survives");
    std::unique_ptr<RigidBodyIntegrator> implicitCopy = roundTrip<RigidBodyIntegrator>(defaults);
    checkSettings(*implicitCopy, defaults);
    check(!implicitCopy->hasExplicitBodies(), "bodies from the System's constraints stay so");
}

void testLangevinSettings() {
    for (bool explicitBodies : {false, true}) {
        std::unique_ptr<RigidBodyLangevinIntegrator> original(explicitBodies ?
                new RigidBodyLangevinIntegrator(310.0, 3.5, 0.003, someBodies) : new RigidBodyLangevinIntegrator(310.0, 3.5, 0.003));
        original->setConstraintTolerance(2e-6);
        original->setIntegrationForceGroups(6);
        original->setRotationMethod(RigidBodyIntegrator::NoSquish);
        original->setRandomNumberSeed(-77);
        original->setMinimumMomentOfInertia(0.021);
        original->setMeasureShadowWork(explicitBodies);
        original->setMeasureHeat(true);
        original->setAccuracyCheck(false);
        checkSettings(*roundTrip<RigidBodyLangevinIntegrator>(*original), *original);
    }
}

/** Positions and velocities after the integrator's steps from the cluster's state. */
void runFrom(const Scene& scene, Integrator& integrator, Platform& platform, int steps, vector<Vec3>& positions,
             vector<Vec3>& velocities) {
    Context context(*scene.system, integrator, platform, platformProperties);
    context.setPositions(scene.positions);
    context.setVelocities(scene.velocities);
    integrator.step(steps);
    State state = context.getState(State::Positions | State::Velocities);
    positions = state.getPositions();
    velocities = state.getVelocities();
}

/** The copy's trajectory from the same state is the original's, bit for bit, for each integrator. */
void testCopyMovesAsTheOriginal(Platform& platform) {
    Scene scene = makeCluster(7, 3, 3, 2, true);
    vector<std::unique_ptr<Integrator> > originals;
    RigidBodyIntegrator* thermostatted = new RigidBodyIntegrator(0.002, scene.bodies);
    thermostatted->setSplitting(RigidBodyIntegrator::Omelyan2);
    thermostatted->setRotationMethod(RigidBodyIntegrator::NoSquish);
    thermostatted->setThermostat(350.0, 0.01);
    thermostatted->setRandomNumberSeed(4321);
    originals.emplace_back(thermostatted);
    RigidBodyLangevinIntegrator* langevin = new RigidBodyLangevinIntegrator(280.0, 20.0, 0.002, scene.bodies);
    langevin->setRandomNumberSeed(99);
    originals.emplace_back(langevin);
    for (auto& original : originals) {
        std::stringstream xml;
        XmlSerializer::serialize<Integrator>(original.get(), "Integrator", xml);
        std::unique_ptr<Integrator> copy(XmlSerializer::deserialize<Integrator>(xml));
        vector<Vec3> r0, v0, r1, v1;
        runFrom(scene, *original, platform, 25, r0, v0);
        runFrom(scene, *copy, platform, 25, r1, v1);
        check(maxDifference(r0, scene.positions) > 0.01, "the molecules moved");
        check(maxDifference(r0, r1) == 0.0 && maxDifference(v0, v1) == 0.0,
              message("the copy's trajectory differs from the original's by ", maxDifference(r0, r1), " nm"));
    }
    // Mid-run: a copy given the original's State (through XML too) continues its trajectory. Setting
    // the State fits the bodies again, which moves them by rounding (3e-16 nm), so to 1e-12 nm.
    RigidBodyIntegrator original(0.002, scene.bodies);
    original.setSplitting(RigidBodyIntegrator::Omelyan4);
    Context context(*scene.system, original, platform, platformProperties);
    context.setPositions(scene.positions);
    context.setVelocities(scene.velocities);
    original.step(15);
    std::stringstream stateXml;
    State midRun = context.getState(State::Positions | State::Velocities);
    XmlSerializer::serialize<State>(&midRun, "State", stateXml);
    std::unique_ptr<State> state(XmlSerializer::deserialize<State>(stateXml));
    std::unique_ptr<RigidBodyIntegrator> copy = roundTrip<RigidBodyIntegrator>(original);
    Context copyContext(*scene.system, *copy, platform, platformProperties);
    copyContext.setState(*state);
    original.step(15);
    copy->step(15);
    State a = context.getState(State::Positions | State::Velocities), b = copyContext.getState(State::Positions | State::Velocities);
    check(maxDifference(a.getPositions(), b.getPositions()) < 1e-12 && maxDifference(a.getVelocities(), b.getVelocities()) < 1e-10,
          message("continued from the State, the copy is ", maxDifference(a.getPositions(), b.getPositions()), " nm off"));
}

/** Earlier versions read with defaults for what they lack. */
void testEarlierVersions() {
    const string bodies = "<Bodies><Body><Particle index=\"0\"/><Particle index=\"1\"/><Particle index=\"2\"/></Body></Bodies>";
    // Version 1: before splittings (every step was Verlet) and the thermostat.
    std::unique_ptr<RigidBodyIntegrator> v1 = fromXml<RigidBodyIntegrator>(
            "<Integrator constraintTolerance=\"3e-07\" explicitBodies=\"1\" integrationForceGroups=\"37\" rotationMethod=\"1\" "
            "stepSize=\".0015\" type=\"RigidBodyIntegrator\" version=\"1\">" + bodies + "</Integrator>");
    ASSERT_EQUAL(RigidBodyIntegrator::Verlet, v1->getSplitting());
    ASSERT_EQUAL(RigidBodyIntegrator::NoSquish, v1->getRotationMethod());
    ASSERT_EQUAL(0.0015, v1->getStepSize());
    ASSERT_EQUAL(3e-7, v1->getConstraintTolerance());
    ASSERT_EQUAL(37, v1->getIntegrationForceGroups());
    check(v1->getExplicitBodies() == vector<vector<int> >({{0, 1, 2}}), "version 1: the bodies");
    check(!v1->hasThermostat(), "version 1: no thermostat");
    // Version 2: the splitting, still no thermostat or seed.
    std::unique_ptr<RigidBodyIntegrator> v2 = fromXml<RigidBodyIntegrator>(
            "<Integrator explicitBodies=\"0\" splitting=\"3\" stepSize=\".002\" type=\"RigidBodyIntegrator\" version=\"2\"/>");
    ASSERT_EQUAL(RigidBodyIntegrator::Omelyan4, v2->getSplitting());
    check(!v2->hasThermostat() && !v2->hasExplicitBodies(), "version 2: no thermostat, bodies from the System");
    ASSERT_EQUAL(RigidBodyIntegrator(0.002).getRandomNumberSeed(), v2->getRandomNumberSeed());
}

void expectXmlError(const string& text, const vector<string>& words) {
    try {
        fromXml<Integrator>(text);
    }
    catch (const OpenMMException& e) {
        for (const string& word : words)
            check(string(e.what()).find(word) != string::npos, "the message names " + word + ": " + e.what());
        return;
    }
    throw OpenMMException("Assertion failure: no exception for " + text);
}

void testBadXml() {
    expectXmlError("<Integrator stepSize=\".002\" type=\"RigidBodyIntegrator\" version=\"5\"/>",
                   {"RigidBodyIntegrator", "version 5", "1 to 4"});
    expectXmlError("<Integrator stepSize=\".002\" type=\"RigidBodyIntegrator\" version=\"0\"/>", {"RigidBodyIntegrator", "version 0"});
    expectXmlError("<Integrator friction=\"1\" stepSize=\".002\" temperature=\"300\" type=\"RigidBodyLangevinIntegrator\" version=\"3\"/>",
                   {"RigidBodyLangevinIntegrator", "version 3", "1 to 2"});
    expectXmlError("<Integrator splitting=\"9\" stepSize=\".002\" type=\"RigidBodyIntegrator\" version=\"3\"/>", {"unknown splitting 9"});
    expectXmlError("<Integrator rotationMethod=\"5\" stepSize=\".002\" type=\"RigidBodyIntegrator\" version=\"3\"/>", {"rotation method"});
    expectXmlError("<Integrator stepSize=\".002\" thermostat=\"1\" thermostatCollisionTime=\"-1\" thermostatTemperature=\"300\" "
                   "type=\"RigidBodyIntegrator\" version=\"3\"/>", {"collision time"});
    expectXmlError("<Integrator friction=\"-2\" stepSize=\".002\" temperature=\"300\" type=\"RigidBodyLangevinIntegrator\" version=\"1\"/>",
                   {"friction"});
    expectXmlError("<Integrator minimumMomentOfInertia=\"-0.01\" stepSize=\".002\" type=\"RigidBodyIntegrator\" version=\"4\"/>",
                   {"RigidBodyIntegrator", "minimum moment of inertia"});
}

int runSerializationTests(Platform& platform) {
    vector<std::pair<string, std::function<void()> > > tests = {
        {"RigidBodyIntegrator: every setting survives XML", []() { testIntegratorSettings(); }},
        {"RigidBodyLangevinIntegrator: every setting survives XML", []() { testLangevinSettings(); }},
        {"a copy moves as the original", [&]() { testCopyMovesAsTheOriginal(platform); }},
        {"earlier versions", []() { testEarlierVersions(); }},
        {"bad XML", []() { testBadXml(); }},
    };
    return runTestList(tests);
}

} // namespace RigidBodyIntegratorTests

int main() {
    return RigidBodyIntegratorTests::runMain([]() -> OpenMM::Platform& {
        registerKernelFactories();  // libOpenMMRigidReference: the kernels for Reference and CPU
        return OpenMM::Platform::getPlatformByName("Reference");
    }, RigidBodyIntegratorTests::runSerializationTests);
}
