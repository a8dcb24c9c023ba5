"""The Python docstrings are the C++ headers' Doxygen (SWIG's -doxygen at build time), in numpy style,
with the Python-only notes of openmmrigid/_pythonapi.py added in one place.

The headers are read here, at test time (the ones installed with the wheel, else the source tree's),
so that no sentence of them is copied into this file: each public method's docstring must hold the
first sentence of the Doxygen comment of its C++ declaration. The notes are checked against the table
that also makes the unit conversions (QUANTITY_ARGUMENTS, QUANTITY_RESULTS), and the table against the
methods' real signatures and results.
"""

import inspect
import pathlib
import pydoc
import re

import numpy as np
import openmm
import openmm.unit as unit
import pytest

import openmmrigid
from openmmrigid import (FreeRotor, RigidBodyBussiIntegrator, RigidBodyIntegrator, RigidBodyIntegratorBase,
                         RigidBodyLangevinIntegrator, special)
from openmmrigid import _pythonapi
from openmmrigid import openmmrigid as swigModule

INTEGRATORS = (RigidBodyIntegratorBase, RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator)
HEADERS = {"RigidBodyIntegratorBase": "RigidBodyIntegratorBase.h", "RigidBodyIntegrator": "RigidBodyIntegrator.h",
           "RigidBodyBussiIntegrator": "RigidBodyBussiIntegrator.h",
           "RigidBodyLangevinIntegrator": "RigidBodyLangevinIntegrator.h", "FreeRotor": "numerics/FreeRotor.h",
           "special": "numerics/Elliptic.h", "platforms": "PlatformSupport.h"}
# What must not survive into a docstring: Doxygen commands and markup, and SWIG's field lists and
# overload markers (the numpy sections replace them).
RAW_MARKUP = re.compile(r"[@\\](param|return|throws|brief|see|ref|f\$|f\[|c |p |a )|</?[bi]>|</?em>|"
                        r"^\s*:(param|type|rtype|return|raises)\b|\*Overload \d+:\*|^\s*\|\s*$", re.MULTILINE)


def _includeFolder():
    installed = pathlib.Path(openmmrigid.__file__).parent / "include"
    if (installed / "RigidBodyIntegrator.h").exists():
        return installed
    return pathlib.Path(__file__).resolve().parents[2] / "openmmapi" / "include"


def _normalized(text):
    return " ".join((text or "").split())


def _doxygenComments(header):
    """{declared name: [first sentence of each Doxygen comment declaring it]} for one header, and the
    comment right before each class, under the class's name."""
    source = (_includeFolder() / HEADERS[header]).read_text(encoding="utf-8")
    found = {}
    for comment, declaration in re.findall(r"/\*\*(.*?)\*/\s*([^;{]*)", source, re.DOTALL):
        text = "\n".join(line.strip().lstrip("*").strip() for line in comment.splitlines())
        text = _normalized(text.split("\n@")[0] if not text.startswith("@") else "")
        if not text:
            continue
        sentence = re.split(r"(?<=[a-z)\]0-9])\. ", text)[0].rstrip(".")
        match = re.search(r"class\s+(?:OPENMM_EXPORT_RIGID\s+)?(\w+)", declaration)
        name = match.group(1) if match else (re.findall(r"(~?\w+)\s*\(", declaration) or [None])[0]
        if name:
            found.setdefault(name, []).append(sentence)
    return found


def _publicMethods(cls):
    """The public methods a class defines itself (not those of openmm.Integrator)."""
    return {name: member for name, member in vars(cls).items()
            if not name.startswith("_") and inspect.isfunction(member)}


def _inHeaders(cls):
    """The Doxygen of cls's header, and of its bases' in this plugin."""
    comments = {}
    for base in reversed(cls.__mro__):
        if base.__name__ in HEADERS:
            for name, sentences in _doxygenComments(base.__name__).items():
                comments.setdefault(name, []).extend(sentences)
    return comments


# ------------------------------------------------------------------------------------------------
# Every docstring comes from the header
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("cls", INTEGRATORS, ids=lambda cls: cls.__name__)
def test_class_docstring_is_the_header_class_comment(cls):
    comments = _doxygenComments(cls.__name__)
    assert cls.__name__ in comments, f"no Doxygen class comment for {cls.__name__}"
    assert comments[cls.__name__][0] in _normalized(cls.__doc__)


#: The public methods each class defines itself (issue 41's lean API); `step` is openmm.Integrator's,
#: defined again by the base (it releases the GIL and issues the AccuracyWarning).
OWN_METHODS = {
    RigidBodyIntegratorBase: {"getRotationMethod", "setRotationMethod", "getMinimumMomentOfInertia",
                              "setMinimumMomentOfInertia", "getForceGroupSubsteps", "setForceGroupSubsteps", "getNumBodies",
                              "getBodyParticles", "computeSystemTemperature", "getMeasureShadowWork", "setMeasureShadowWork",
                              "getShadowWork", "getHeat", "getAccuracyCheck", "setAccuracyCheck", "step"},
    RigidBodyIntegrator: {"getSplitting", "setSplitting"},
    RigidBodyBussiIntegrator: {"getTemperature", "setTemperature", "getCollisionTime", "setCollisionTime",
                               "getRandomNumberSeed", "setRandomNumberSeed"},
    RigidBodyLangevinIntegrator: {"getTemperature", "setTemperature", "getFriction", "setFriction", "getRandomNumberSeed",
                                  "setRandomNumberSeed", "getOnStepKineticEnergy"},
}


@pytest.mark.parametrize("cls", INTEGRATORS, ids=lambda cls: cls.__name__)
def test_the_documented_methods_are_the_lean_api(cls):
    """The methods whose docstrings are checked below are exactly the public API of each class."""
    assert set(_publicMethods(cls)) == OWN_METHODS[cls]


@pytest.mark.parametrize("cls", INTEGRATORS, ids=lambda cls: cls.__name__)
def test_every_public_method_has_its_header_doxygen(cls):
    comments = _inHeaders(cls)
    methods = _publicMethods(cls)
    assert methods
    for name, method in methods.items():
        doc = _normalized(method.__doc__)
        assert doc, f"{cls.__name__}.{name} has no docstring"
        assert name in comments, f"{cls.__name__}.{name} has no Doxygen comment in the headers"
        assert any(sentence in doc for sentence in comments[name]), \
            f"{cls.__name__}.{name}: none of {comments[name]} is in its docstring {doc!r}"


@pytest.mark.parametrize("cls", [RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator],
                         ids=lambda cls: cls.__name__)
def test_constructors_are_documented_in_the_class_docstring(cls):
    """numpy's convention: the class docstring has the constructor's Parameters (a parameter that only
    some overloads take is optional); __init__ lists each overload with its header comment."""
    sentences = _doxygenComments(cls.__name__)[cls.__name__]
    constructorComments = [sentence for sentence in sentences if sentence.startswith("Create")]
    assert len(constructorComments) == 2
    for sentence in constructorComments:
        assert sentence in _normalized(cls.__init__.__doc__)
    assert "Parameters\n----------" in cls.__doc__
    assert re.search(r"^bodies : list of list of int, optional$", cls.__doc__, re.MULTILINE)


def test_freerotor_docstrings_are_the_header_doxygen():
    comments = _doxygenComments("FreeRotor")
    assert comments["FreeRotor"][0] in _normalized(FreeRotor.__doc__)
    assert "Create the rotor from its initial state" in comments["FreeRotor"]  # the constructor's, after the class's
    assert comments["evolve"][0] in _normalized(FreeRotor.evolve.__doc__)
    properties = [name for name, member in vars(FreeRotor).items() if isinstance(member, property)]
    assert len(properties) == 8
    for name in properties:
        getter = "get" + name[0].upper() + name[1:]
        doc = _normalized(getattr(FreeRotor, name).__doc__)
        # numpy's property form, "type: The x ..." for the getter's "Get the x ...".
        assert re.match(r"^[\w.]+(, shape \([\d, ]+\))?: ", doc), doc
        assert any(sentence.replace("Get the ", "The ", 1) in doc for sentence in comments[getter]), (name, doc)


def test_special_functions_are_the_header_doxygen():
    comments = _doxygenComments("special")
    for name in special.__all__:
        function = getattr(special, name)
        doc = _normalized(function.__doc__)
        assert comments[name][0] in doc, (name, doc)
        # The Python function's parameters are the documented ones; a default is marked optional.
        for parameter in inspect.signature(function).parameters.values():
            optional = ", optional" if parameter.default is not inspect.Parameter.empty else ""
            assert re.search(rf"^{parameter.name} : float{optional}$", function.__doc__, re.MULTILINE), \
                (name, parameter.name)
    # jacobiElliptic's C++ outputs (@param[out]) are its Python results, in the tuple's order.
    returns = special.jacobiElliptic.__doc__.split("Returns\n-------\n")[1]
    assert re.findall(r"^(\w+) : float$", returns, re.MULTILINE)[:3] == ["sn", "cn", "dn"]
    assert "Parameters" in special.ellipticK.__doc__ and "sn :" not in special.ellipticK.__doc__


def test_module_functions_are_the_header_doxygen():
    comments = _doxygenComments("platforms")
    assert comments["getSupportedPlatforms"][0] in _normalized(openmmrigid.getSupportedPlatforms.__doc__)


# ------------------------------------------------------------------------------------------------
# They read as Python documentation
# ------------------------------------------------------------------------------------------------

def _allDocumented():
    for cls in INTEGRATORS + (FreeRotor,):
        yield cls.__name__, cls.__doc__
        for name, member in vars(cls).items():
            if isinstance(member, property) or inspect.isfunction(member):
                yield f"{cls.__name__}.{name}", member.__doc__
    for name in special.__all__:
        yield f"special.{name}", getattr(special, name).__doc__
    yield "getSupportedPlatforms", openmmrigid.getSupportedPlatforms.__doc__


#: What issue 41 removed from the integrators: no docstring may send a user to it.
REMOVED = ["setThermostat", "removeThermostat", "hasThermostat", "getThermostatTemperature", "getThermostatCollisionTime",
           "getThermostatWork", "setMeasureHeat", "getMeasureHeat", "getShadowWorkInKT", "getHeatInKT", "resetShadowWork",
           "resetHeat", "getAccuracyWarning", "getBodyKind", "getBodyMoments", "getBodyMassMoments",
           "getTranslationalKineticEnergy", "getRotationalKineticEnergy", "getNumDegreesOfFreedom",
           "getNumForceEvaluations", "hasExplicitBodies", "getExplicitBodies", "getClassName", "getVelocityTimeOffset",
           "NoThermostatError", "openmmrigid.testing"]


def test_no_docstring_names_a_removed_method():
    documented = list(_allDocumented()) + [("deserializeIntegrator", openmmrigid.deserializeIntegrator.__doc__),
                                           ("AccuracyWarning", openmmrigid.AccuracyWarning.__doc__),
                                           ("openmmrigid", openmmrigid.__doc__)]
    named = [(name, removed) for name, doc in documented for removed in REMOVED if doc and removed in doc]
    assert not named, named


def test_no_raw_doxygen_or_field_lists():
    for name, doc in _allDocumented():
        if doc:
            match = RAW_MARKUP.search(doc)
            assert match is None, f"{name}: {match.group(0)!r} in {doc!r}"


def test_exceptions_are_named_as_python_sees_them():
    """Every C++ exception reaches Python as openmm.OpenMMException (python/openmmrigid.i)."""
    count = 0
    for name, doc in _allDocumented():
        if doc and "Raises\n------" in doc:
            count += 1
            raised = doc.split("Raises\n------\n")[1].splitlines()[0]
            assert raised == "openmm.OpenMMException", (name, raised)
        assert "std::" not in (doc or ""), name
    assert count >= 8


@pytest.mark.parametrize("cls", INTEGRATORS + (FreeRotor,), ids=lambda cls: cls.__name__)
def test_help_reads_well(cls):
    text = pydoc.render_doc(cls, renderer=pydoc.plaintext)
    assert RAW_MARKUP.search(text.replace(" |  ", "")) is None
    for section in ("Parameters", "Returns"):
        assert section in text
    # Continuation lines of a description are re-indented with it (no header alignment left over).
    assert not re.search(r"\n \|\s{20,}\S", text)


# ------------------------------------------------------------------------------------------------
# The Python-only notes: made from the same table as the unit conversions
# ------------------------------------------------------------------------------------------------

def _class(name):
    return getattr(openmmrigid, name)


def _parameterEntry(doc, name):
    match = re.search(rf"^{name} : (.*)\n((?:    .*\n?)+)", doc, re.MULTILINE)
    assert match, f"no parameter {name} in {doc!r}"
    return match.group(1), match.group(2)


@pytest.mark.parametrize("key", sorted(_pythonapi.QUANTITY_ARGUMENTS), ids="{0[0]}.{0[1]}".format)
def test_quantity_arguments_are_noted(key):
    className, methodName = key
    cls = _class(className)
    # A constructor's parameters are documented in the class docstring.
    doc = cls.__doc__ if methodName == "__init__" else getattr(cls, methodName).__doc__
    for name, argumentUnit in _pythonapi.QUANTITY_ARGUMENTS[key]:
        pythonType, description = _parameterEntry(doc, name)
        assert pythonType == "float or openmm.unit.Quantity"
        assert f"converted to {_pythonapi.unitName(argumentUnit)}" in description


@pytest.mark.parametrize("key", sorted(_pythonapi.QUANTITY_ARGUMENTS), ids="{0[0]}.{0[1]}".format)
def test_quantity_arguments_match_the_cpp_signature(key):
    """The table's names and order are those of the C++ parameters (SWIG's docstring, before the
    conversion wrapped the method), so the positions it converts are the right ones."""
    className, methodName = key
    wrapped = getattr(_class(className), methodName).__wrapped__
    names = [name for name, _ in _pythonapi.QUANTITY_ARGUMENTS[key]]
    for overload in _pythonapi._overloads(wrapped.__doc__):
        documented = [entry.name for entry in _pythonapi.Parsed(overload).parameters]
        assert documented[:len(names)] == names, (documented, names)
    signature = [name for name in inspect.signature(wrapped).parameters if name != "self"]
    if signature != ["args"]:  # SWIG's overload dispatcher takes *args
        assert signature[:len(names)] == names


def test_quantity_arguments_are_converted():
    femtosecond = unit.femtoseconds
    integrator = RigidBodyIntegrator(2 * femtosecond)
    assert integrator.getStepSize() == 0.002 * unit.picoseconds
    integrator.setMinimumMomentOfInertia(0.02 * unit.amu * unit.angstrom**2)
    assert np.isclose(integrator.getMinimumMomentOfInertia().value_in_unit(unit.amu * unit.nanometer**2), 0.0002)
    bussi = RigidBodyBussiIntegrator(300 * unit.kelvin, 100 * femtosecond, 4 * femtosecond)
    assert bussi.getTemperature() == 300 * unit.kelvin
    assert np.isclose(bussi.getCollisionTime().value_in_unit(unit.picosecond), 0.1)
    assert bussi.getStepSize() == 0.004 * unit.picoseconds
    bussi.setTemperature(temperature=310 * unit.kelvin)  # by keyword too
    bussi.setCollisionTime(collisionTime=0.5 * unit.picosecond)
    assert bussi.getTemperature() == 310 * unit.kelvin and bussi.getCollisionTime() == 0.5 * unit.picosecond
    langevin = RigidBodyLangevinIntegrator(300 * unit.kelvin, 0.001 / femtosecond, 4 * femtosecond)
    assert langevin.getTemperature() == 300 * unit.kelvin
    assert np.isclose(langevin.getFriction().value_in_unit(unit.picosecond**-1), 1.0)
    assert langevin.getStepSize() == 0.004 * unit.picoseconds
    langevin.setTemperature(temp=310 * unit.kelvin)   # by keyword too
    langevin.setFriction(coeff=2 / unit.picosecond)
    assert langevin.getTemperature() == 310 * unit.kelvin and langevin.getFriction() == 2 / unit.picosecond


@pytest.mark.parametrize("key", sorted(_pythonapi.QUANTITY_RESULTS), ids="{0[0]}.{0[1]}".format)
def test_quantity_results_are_noted(key):
    className, methodName = key
    doc = getattr(_class(className), methodName).__doc__
    returns = doc.split("Returns\n-------\n")[1]
    assert returns.startswith("openmm.unit.Quantity\n")
    assert f"a Quantity, in {_pythonapi.unitName(_pythonapi.QUANTITY_RESULTS[key])}" in returns


def test_quantity_results_are_quantities():
    """Each getter in the table returns a Quantity of its unit (on a bound integrator)."""
    system = openmm.System()
    for _ in range(3):
        system.addParticle(1.0)
    positions = [openmm.Vec3(0, 0, 0), openmm.Vec3(0.1, 0, 0), openmm.Vec3(0, 0.12, 0)]
    leading = {RigidBodyIntegrator: (), RigidBodyBussiIntegrator: (300, 0.1), RigidBodyLangevinIntegrator: (300, 1)}
    for cls in (RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator):
        integrator = cls(*leading[cls], 0.001, [[0, 1, 2]])
        integrator.setMeasureShadowWork(True)  # getShadowWork() and getHeat() need them measured
        context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("Reference"))
        context.setPositions(positions)
        context.setVelocitiesToTemperature(300, 1)
        checked = 0
        for (className, methodName), resultUnit in _pythonapi.QUANTITY_RESULTS.items():
            if not issubclass(cls, _class(className)):
                continue
            method = getattr(integrator, methodName)
            arguments = [0] if list(inspect.signature(method.__wrapped__).parameters) == ["self", "index"] else []
            value = method(*arguments)
            assert unit.is_quantity(value) and value.unit.is_compatible(resultUnit), (methodName, value)
            assert np.all(np.isfinite(value.value_in_unit(resultUnit)))
            checked += 1
        assert checked == sum(1 for className, _ in _pythonapi.QUANTITY_RESULTS if issubclass(cls, _class(className)))
        assert checked >= 4
        del context


def test_methods_not_in_the_tables_return_plain_values():
    """The tables are the only place that makes Quantities: a getter outside them returns the C++ value."""
    integrator = RigidBodyBussiIntegrator(300, 0.1, 0.001)
    for name in ("getRotationMethod", "getSplitting", "getRandomNumberSeed", "getMeasureShadowWork", "getAccuracyCheck"):
        assert all((className, name) not in _pythonapi.QUANTITY_RESULTS
                   for className in ("RigidBodyIntegratorBase", "RigidBodyIntegrator", "RigidBodyBussiIntegrator"))
        assert isinstance(getattr(integrator, name)(), (int, bool))
        assert not unit.is_quantity(getattr(integrator, name)())
        assert "Quantity" not in getattr(RigidBodyBussiIntegrator, name).__doc__
    assert RigidBodyIntegrator(0.001, [[0, 1]]).getNumBodies() == 1


def test_numpy_shapes_of_freerotor():
    """FreeRotor's Python-only notes: the numpy shapes it takes and returns, as evolve really gives them."""
    assert _parameterEntry(FreeRotor.__doc__, "moments")[0] == "array_like, shape (3,)"
    assert _parameterEntry(FreeRotor.__doc__, "attitude")[0] == "array_like, shape (3, 3), optional"
    assert "checkInput" not in FreeRotor.__doc__  # C++ only
    returns = FreeRotor.evolve.__doc__.split("Returns\n-------\n")[1]
    assert "omega : numpy.ndarray, shape (3,) or (n, 3)" in returns
    assert "attitude : numpy.ndarray, shape (3, 3) or (n, 3, 3)" in returns
    omegas, attitudes = FreeRotor([1.0, 2.0, 3.0], [0.1, 1.0, 0.2]).evolve(np.linspace(0.0, 1.0, 5))
    assert omegas.shape == (5, 3) and attitudes.shape == (5, 3, 3)


def test_swig_docstrings_are_doxygen():
    """The build ran SWIG with -doxygen: the proxy's docstrings carry the headers' @param names."""
    assert ":param stepSize:" in swigModule.RigidBodyIntegrator.__init__.__wrapped__.__doc__
    assert ":param m1:" in swigModule.ellipticK.__doc__
