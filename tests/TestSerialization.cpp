/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * XML serialization of RigidBodyIntegrator, RigidBodyBussiIntegrator and    *
 * RigidBodyLangevinIntegrator (serialization/), on the Reference platform:   *
 * - a round trip through XmlSerializer keeps every setting, each one set     *
 *   away from its default, and the class; the bodies, explicit or found in   *
 *   the System, are those of the original once bound to a Context;           *
 * - the copy moves as the original does, bit for bit: from the same state    *
 *   (the stochastic ones too, with the same seed), and from a State read     *
 *   mid-run, itself serialized;                                              *
 * - files of earlier versions read with the defaults of what they lack; a   *
 *   RigidBodyIntegrator with a thermostat (versions 3 and 4) reads as a      *
 *   RigidBodyBussiIntegrator, measureHeat as measureShadowWork;              *
 *   unknown versions and bad values are an OpenMMException that says so.    *
 * -------------------------------------------------------------------------- */

#include "RigidBodyTestSystems.h"
#include "openmm/serialization/XmlSerializer.h"
#include <regex>

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

/** The XML of an integrator. */
string toXml(const Integrator& integrator) {
    std::stringstream xml;
    XmlSerializer::serialize<Integrator>(&integrator, "Integrator", xml);
    return xml.str();
}

/** The value of an attribute of the XML's Integrator element ("" if it has none). */
string attribute(const string& xml, const string& name) {
    const size_t start = xml.find("<Integrator");
    if (start == string::npos)
        return "";
    const string element = xml.substr(start, xml.find('>', start) - start);
    std::smatch match;
    if (std::regex_search(element, match, std::regex("\\s" + name + "=\"([^\"]*)\"")))
        return match[1];
    return "";
}

/**
 * The bodies an integrator moves once bound to a Context (getBodyParticles() of each body): the
 * System is smallSystem() with each of `clusters` held rigid by constraints (a triangle of them), which
 * the integrator takes as a body if its bodies are not explicit. The Context binds the integrator
 * for good: call it on integrators that are used no further.
 */
vector<vector<int> > boundBodies(Integrator& integrator, const vector<vector<int> >& clusters) {
    std::unique_ptr<System> system(smallSystem());
    for (const vector<int>& cluster : clusters)
        for (size_t i = 0; i < cluster.size(); i++)
            for (size_t j = i + 1; j < cluster.size(); j++) {
                Vec3 d = smallPositions[cluster[i]] - smallPositions[cluster[j]];
                system->addConstraint(cluster[i], cluster[j], sqrt(d.dot(d)));
            }
    Context context(*system, integrator, Platform::getPlatformByName("Reference"));
    context.setPositions(smallPositions);
    RigidBodyIntegratorBase& rigid = dynamic_cast<RigidBodyIntegratorBase&>(integrator);
    vector<vector<int> > bodies;
    for (int b = 0; b < rigid.getNumBodies(); b++)
        bodies.push_back(rigid.getBodyParticles(b));
    return bodies;
}

/** The rigid triangle of smallPositions the bound integrators of checkBaseSettings() find if their bodies are not explicit. */
const vector<vector<int> > foundCluster = {{0, 1, 2}};

void checkBaseSettings(RigidBodyIntegratorBase& copy, RigidBodyIntegratorBase& original) {
    ASSERT_EQUAL(original.getStepSize(), copy.getStepSize());
    ASSERT_EQUAL(original.getConstraintTolerance(), copy.getConstraintTolerance());
    ASSERT_EQUAL(original.getIntegrationForceGroups(), copy.getIntegrationForceGroups());
    ASSERT_EQUAL(original.getRotationMethod(), copy.getRotationMethod());
    ASSERT_EQUAL(original.getMinimumMomentOfInertia(), copy.getMinimumMomentOfInertia());
    ASSERT_EQUAL(original.getMeasureShadowWork(), copy.getMeasureShadowWork());
    ASSERT_EQUAL(original.getAccuracyCheck(), copy.getAccuracyCheck());
    check(toXml(copy).find("measureHeat") == string::npos, "the XML has no measureHeat any more");
    // The bodies: bound to a Context, each moves the same ones.
    check(boundBodies(original, foundCluster) == boundBodies(copy, foundCluster), "the bodies survive the round trip");
}

/** Whether the integrator is a RigidBodyBussiIntegrator (a RigidBodyIntegrator with a thermostat). */
const RigidBodyBussiIntegrator* asBussi(const RigidBodyIntegrator& integrator) {
    return dynamic_cast<const RigidBodyBussiIntegrator*>(&integrator);
}

void checkSettings(RigidBodyIntegrator& copy, RigidBodyIntegrator& original) {
    ASSERT_EQUAL(original.getSplitting(), copy.getSplitting());
    check((asBussi(original) != nullptr) == (asBussi(copy) != nullptr), "the copy has a thermostat if and only if the original has");
    if (const RigidBodyBussiIntegrator* bussi = asBussi(original)) {
        ASSERT_EQUAL(bussi->getTemperature(), asBussi(copy)->getTemperature());
        ASSERT_EQUAL(bussi->getCollisionTime(), asBussi(copy)->getCollisionTime());
        ASSERT_EQUAL(bussi->getRandomNumberSeed(), asBussi(copy)->getRandomNumberSeed());
    }
    checkBaseSettings(copy, original);
}

void checkSettings(RigidBodyLangevinIntegrator& copy, RigidBodyLangevinIntegrator& original) {
    ASSERT_EQUAL(original.getTemperature(), copy.getTemperature());
    ASSERT_EQUAL(original.getFriction(), copy.getFriction());
    ASSERT_EQUAL(original.getRandomNumberSeed(), copy.getRandomNumberSeed());
    checkBaseSettings(copy, original);
}

const vector<vector<int> > someBodies = {{0, 1, 2}, {5}, {3, 4}};

/**
 * Every setting of RigidBodyIntegrator and RigidBodyBussiIntegrator away from its default, in every
 * combination that differs; each class written as its own type, RigidBodyIntegrator without the
 * thermostat's fields.
 */
void testIntegratorSettings() {
    for (RigidBodyIntegrator::Splitting splitting : allSplittings) {
        for (bool thermostat : {false, true}) {
            RigidBodyIntegrator defaults(0.002);
            RigidBodyBussiIntegrator bussiDefaults(300.0, 1.0, 0.002);
            std::unique_ptr<RigidBodyIntegrator> original(thermostat ? new RigidBodyBussiIntegrator(251.5, 0.07, 0.0015, someBodies) :
                                                          new RigidBodyIntegrator(0.0015, someBodies));
            original->setConstraintTolerance(3e-7);
            original->setIntegrationForceGroups(37);
            original->setRotationMethod(RigidBodyIntegrator::NoSquish);
            original->setMinimumMomentOfInertia(0.0375);
            original->setSplitting(splitting);
            if (thermostat)
                dynamic_cast<RigidBodyBussiIntegrator&>(*original).setRandomNumberSeed(12345);
            original->setMeasureShadowWork(true);
            original->setAccuracyCheck(false);
            check(original->getConstraintTolerance() != defaults.getConstraintTolerance() &&
                  original->getIntegrationForceGroups() != defaults.getIntegrationForceGroups() &&
                  original->getMinimumMomentOfInertia() != defaults.getMinimumMomentOfInertia() &&
                  original->getMeasureShadowWork() != defaults.getMeasureShadowWork() &&
                  original->getAccuracyCheck() != defaults.getAccuracyCheck() &&
                  (!thermostat || asBussi(*original)->getRandomNumberSeed() != bussiDefaults.getRandomNumberSeed()),
                  "the settings differ from the defaults");
            const string xml = toXml(*original);
            check(attribute(xml, "type") == (thermostat ? "RigidBodyBussiIntegrator" : "RigidBodyIntegrator") &&
                  attribute(xml, "version") == (thermostat ? "1" : "5"), "the type and version written: " + xml);
            check(thermostat || xml.find("thermostat") == string::npos, "RigidBodyIntegrator writes no thermostat: " + xml);
            if (thermostat)
                checkSettings(*roundTrip<RigidBodyBussiIntegrator>(*original), *original);
            else
                checkSettings(*roundTrip<RigidBodyIntegrator>(*original), *original);
        }
    }
    // Bodies found in the System (no list) and an explicit empty list (every particle free) are
    // different settings: bound, one finds the System's rigid cluster, the other moves no body.
    RigidBodyIntegrator empty(0.002, vector<vector<int> >());
    std::unique_ptr<RigidBodyIntegrator> emptyCopy = roundTrip<RigidBodyIntegrator>(empty);
    check(boundBodies(*emptyCopy, foundCluster).empty(), "an explicit empty list of bodies survives");
    for (bool thermostat : {false, true}) {
        std::unique_ptr<RigidBodyIntegrator> implicit(thermostat ? new RigidBodyBussiIntegrator(300.0, 0.1, 0.002) :
                                                      new RigidBodyIntegrator(0.002));
        std::unique_ptr<RigidBodyIntegrator> implicitCopy = roundTrip<RigidBodyIntegrator>(*implicit);
        check(boundBodies(*roundTrip<RigidBodyIntegrator>(*implicitCopy), foundCluster) == foundCluster,
              "bodies from the System's constraints stay so");
        checkSettings(*implicitCopy, *implicit);
    }
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
    RigidBodyBussiIntegrator* thermostatted = new RigidBodyBussiIntegrator(350.0, 0.01, 0.002, scene.bodies);
    thermostatted->setSplitting(RigidBodyIntegrator::Omelyan2);
    thermostatted->setRotationMethod(RigidBodyIntegrator::NoSquish);
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
    // Bound to a System whose rigid cluster is {3, 4, 5}: explicit bodies are those of the file.
    const vector<vector<int> > otherCluster = {{3, 4, 5}};
    // Version 1: before splittings (every step was Verlet) and the thermostat.
    std::unique_ptr<RigidBodyIntegrator> v1 = fromXml<RigidBodyIntegrator>(
            "<Integrator constraintTolerance=\"3e-07\" explicitBodies=\"1\" integrationForceGroups=\"37\" rotationMethod=\"1\" "
            "stepSize=\".0015\" type=\"RigidBodyIntegrator\" version=\"1\">" + bodies + "</Integrator>");
    ASSERT_EQUAL(RigidBodyIntegrator::Verlet, v1->getSplitting());
    ASSERT_EQUAL(RigidBodyIntegrator::NoSquish, v1->getRotationMethod());
    ASSERT_EQUAL(0.0015, v1->getStepSize());
    ASSERT_EQUAL(3e-7, v1->getConstraintTolerance());
    ASSERT_EQUAL(37, v1->getIntegrationForceGroups());
    check(!v1->getMeasureShadowWork(), "version 1: nothing measured");
    check(asBussi(*v1) == nullptr, "version 1: no thermostat");
    ASSERT_EQUAL(1, v1->getNumBodies());
    check(boundBodies(*v1, otherCluster) == vector<vector<int> >({{0, 1, 2}}), "version 1: the bodies");
    // Version 2: the splitting, still no thermostat or seed.
    std::unique_ptr<RigidBodyIntegrator> v2 = fromXml<RigidBodyIntegrator>(
            "<Integrator explicitBodies=\"0\" splitting=\"3\" stepSize=\".002\" type=\"RigidBodyIntegrator\" version=\"2\"/>");
    ASSERT_EQUAL(RigidBodyIntegrator::Omelyan4, v2->getSplitting());
    check(asBussi(*v2) == nullptr, "version 2: no thermostat");
    check(boundBodies(*v2, otherCluster) == otherCluster, "version 2: bodies from the System");
    // Versions 3 and 4 with the thermostat on: a RigidBodyBussiIntegrator with its bath, seed and
    // splitting; measureHeat="1" measures the shadow work (and the heat) too.
    for (int version : {3, 4}) {
        const string what = message("version ", version, " with a thermostat: ");
        std::unique_ptr<RigidBodyIntegrator> old = fromXml<RigidBodyIntegrator>(
                "<Integrator explicitBodies=\"1\" measureHeat=\"1\" measureShadowWork=\"0\" randomSeed=\"77\" rotationMethod=\"1\" "
                "splitting=\"1\" stepSize=\".0025\" thermostat=\"1\" thermostatCollisionTime=\"0.2\" thermostatTemperature=\"310.5\" "
                "type=\"RigidBodyIntegrator\" version=\"" + std::to_string(version) + "\">" + bodies + "</Integrator>");
        const RigidBodyBussiIntegrator* bussi = asBussi(*old);
        check(bussi != nullptr, what + "not a RigidBodyBussiIntegrator");
        ASSERT_EQUAL(310.5, bussi->getTemperature());
        ASSERT_EQUAL(0.2, bussi->getCollisionTime());
        ASSERT_EQUAL(77, bussi->getRandomNumberSeed());
        ASSERT_EQUAL(0.0025, bussi->getStepSize());
        ASSERT_EQUAL(RigidBodyIntegrator::Omelyan2, bussi->getSplitting());
        ASSERT_EQUAL(RigidBodyIntegrator::NoSquish, bussi->getRotationMethod());
        check(bussi->getMeasureShadowWork(), what + "measureHeat=\"1\" does not measure");
        check(boundBodies(*old, otherCluster) == vector<vector<int> >({{0, 1, 2}}), what + "the bodies");
        // Written again, it is a RigidBodyBussiIntegrator of the current version.
        const string xml = toXml(*fromXml<RigidBodyIntegrator>(toXml(*fromXml<RigidBodyIntegrator>(
                "<Integrator explicitBodies=\"0\" stepSize=\".002\" thermostat=\"1\" thermostatCollisionTime=\"0.2\" "
                "thermostatTemperature=\"310.5\" type=\"RigidBodyIntegrator\" version=\"" + std::to_string(version) + "\"/>"))));
        check(attribute(xml, "type") == "RigidBodyBussiIntegrator" && attribute(xml, "version") == "1" &&
              attribute(xml, "temperature") != "" && xml.find("measureHeat") == string::npos, what + "written again as " + xml);
    }
    // Versions 3 and 4 with the thermostat off: a RigidBodyIntegrator; measureHeat="1" alone measures.
    std::unique_ptr<RigidBodyIntegrator> v4 = fromXml<RigidBodyIntegrator>(
            "<Integrator explicitBodies=\"0\" measureHeat=\"1\" randomSeed=\"5\" stepSize=\".002\" thermostat=\"0\" "
            "thermostatCollisionTime=\"0.1\" thermostatTemperature=\"300\" type=\"RigidBodyIntegrator\" version=\"4\"/>");
    check(asBussi(*v4) == nullptr, "version 4 without a thermostat: a RigidBodyIntegrator");
    check(v4->getMeasureShadowWork(), "version 4: measureHeat=\"1\" does not measure");
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
    expectXmlError("<Integrator stepSize=\".002\" type=\"RigidBodyIntegrator\" version=\"6\"/>",
                   {"RigidBodyIntegrator", "version 6", "1 to 5"});
    expectXmlError("<Integrator collisionTime=\"0.1\" stepSize=\".002\" temperature=\"300\" type=\"RigidBodyBussiIntegrator\" "
                   "version=\"2\"/>", {"RigidBodyBussiIntegrator", "version 2", "1 to 1"});
    expectXmlError("<Integrator collisionTime=\"0.1\" stepSize=\".002\" temperature=\"300\" type=\"RigidBodyBussiIntegrator\" "
                   "version=\"0\"/>", {"RigidBodyBussiIntegrator", "version 0"});
    expectXmlError("<Integrator collisionTime=\"0\" stepSize=\".002\" temperature=\"300\" type=\"RigidBodyBussiIntegrator\" "
                   "version=\"1\"/>", {"collision time"});
    expectXmlError("<Integrator collisionTime=\"0.1\" stepSize=\".002\" temperature=\"-3\" type=\"RigidBodyBussiIntegrator\" "
                   "version=\"1\"/>", {"temperature"});
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
        {"RigidBodyIntegrator and RigidBodyBussiIntegrator: every setting survives XML", []() { testIntegratorSettings(); }},
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
