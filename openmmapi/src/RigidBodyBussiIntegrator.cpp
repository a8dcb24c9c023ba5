#include "RigidBodyBussiIntegrator.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <sstream>
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

RigidBodyBussiIntegrator::RigidBodyBussiIntegrator(double temperature, double collisionTime, double stepSize) :
        RigidBodyIntegrator("RigidBodyBussiIntegrator", stepSize), randomNumberSeed(0) {
    setTemperature(temperature);
    setCollisionTime(collisionTime);
}

RigidBodyBussiIntegrator::RigidBodyBussiIntegrator(double temperature, double collisionTime, double stepSize,
                                                   const vector<vector<int> >& bodies) :
        RigidBodyIntegrator("RigidBodyBussiIntegrator", stepSize, bodies), randomNumberSeed(0) {
    setTemperature(temperature);
    setCollisionTime(collisionTime);
}

void RigidBodyBussiIntegrator::setTemperature(double temperature) {
    if (!(isfinite(temperature) && temperature >= 0.0)) {
        stringstream text;
        text.precision(17);
        text << "RigidBodyBussiIntegrator: the temperature must be finite and >= 0 K; got " << temperature;
        throw OpenMMException(text.str());
    }
    bath.temperature = temperature;
}

void RigidBodyBussiIntegrator::setCollisionTime(double collisionTime) {
    if (!(isfinite(collisionTime) && collisionTime > 0.0)) {
        stringstream text;
        text.precision(17);
        text << "RigidBodyBussiIntegrator: the collision time must be finite and > 0 ps; got " << collisionTime;
        throw OpenMMException(text.str());
    }
    bath.collisionTime = collisionTime;
}

} // namespace OpenMMRigid
