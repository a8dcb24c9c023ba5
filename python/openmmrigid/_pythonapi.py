"""What the Python API adds to the C++ one, and the docstrings that say so.

The docstrings of the SWIG proxies (openmmrigid/openmmrigid.py) are the C++ headers' Doxygen,
translated by SWIG's ``-doxygen`` at build time into Sphinx field lists (``:param x:``, ``:rtype:``,
``:raises:``). This module turns them into the numpy-style sections OpenMM's own docstrings use, and
adds, in one place each, what only Python has:

- ``QUANTITY_ARGUMENTS`` and ``QUANTITY_RESULTS``: the arguments that accept an ``openmm.unit``
  Quantity and the methods that return one, as OpenMM's wrappers do. The same table makes the
  conversion and writes the note, so the two cannot disagree.
- ``fromCpp()``: a pure-Python function that wraps a C++ one takes the C++ docstring, plus the notes
  of what the Python function does differently (defaults, accepted types).

Every C++ exception reaches Python as ``openmm.OpenMMException`` (the ``%exception`` handler of
python/openmmrigid.i), so a ``@throws`` of any C++ exception is listed under that name.
"""

import functools
import inspect
import re
import textwrap

from openmm import unit

__all__ = ["QUANTITY_ARGUMENTS", "QUANTITY_RESULTS", "numpyStyle", "fromCpp", "propertyDoc", "applyToClasses"]

#: (class name, method name) -> the leading arguments that accept an openmm.unit Quantity, in their
#: positional order after self, each with the unit it is converted to; plain numbers are taken as
#: being in that unit. Constructors are listed as "__init__" (SWIG's overload dispatcher takes *args,
#: so the position matters; keywords are converted too where the method takes them).
QUANTITY_ARGUMENTS = {
    ("RigidBodyIntegrator", "__init__"): (("stepSize", unit.picosecond),),
    ("RigidBodyBussiIntegrator", "__init__"): (("temperature", unit.kelvin), ("collisionTime", unit.picosecond),
                                               ("stepSize", unit.picosecond)),
    ("RigidBodyBussiIntegrator", "setTemperature"): (("temperature", unit.kelvin),),
    ("RigidBodyBussiIntegrator", "setCollisionTime"): (("collisionTime", unit.picosecond),),
    ("RigidBodyLangevinIntegrator", "__init__"): (("temperature", unit.kelvin),
                                                  ("frictionCoeff", unit.picosecond**-1),
                                                  ("stepSize", unit.picosecond)),
    ("RigidBodyLangevinIntegrator", "setTemperature"): (("temp", unit.kelvin),),
    ("RigidBodyLangevinIntegrator", "setFriction"): (("coeff", unit.picosecond**-1),),
    ("RigidBodyIntegratorBase", "setMinimumMomentOfInertia"): (("moment", unit.amu * unit.nanometer**2),),
}

#: (class name, method name) -> the unit of the Quantity the method returns (the C++ returns the number
#: in that unit).
QUANTITY_RESULTS = {
    ("RigidBodyIntegratorBase", "getMinimumMomentOfInertia"): unit.amu * unit.nanometer**2,
    ("RigidBodyIntegratorBase", "computeSystemTemperature"): unit.kelvin,
    ("RigidBodyIntegratorBase", "getShadowWork"): unit.kilojoule_per_mole,
    ("RigidBodyIntegratorBase", "getHeat"): unit.kilojoule_per_mole,
    ("RigidBodyBussiIntegrator", "getTemperature"): unit.kelvin,
    ("RigidBodyBussiIntegrator", "getCollisionTime"): unit.picosecond,
    ("RigidBodyLangevinIntegrator", "getTemperature"): unit.kelvin,
    ("RigidBodyLangevinIntegrator", "getFriction"): unit.picosecond**-1,
    ("RigidBodyLangevinIntegrator", "getOnStepKineticEnergy"): unit.kilojoule_per_mole,
}

QUANTITY = "openmm.unit.Quantity"
_PYTHON_EXCEPTION = "openmm.OpenMMException"


# ------------------------------------------------------------------------------------------------
# SWIG's field lists -> numpy-style sections
# ------------------------------------------------------------------------------------------------

_FIELD = re.compile(r"^:(type|param|rtype|return|raises)(?: ([A-Za-z_]\w*))?:\s*(.*)$")
_OVERLOAD = re.compile(r"^\*Overload \d+:\*$")


class _Entry:
    """One parameter, result or exception: a name (or None), a type, its description lines (as SWIG
    wrote them) and the Python-only notes added to them."""

    def __init__(self, name=None, type=None):
        self.name, self.type, self.lines, self.notes = name, type, [], []

    def description(self):
        # SWIG keeps the header's alignment on continuation lines: dedent them as one block, so that
        # the relative indentation of a list inside a description survives.
        first, rest = (self.lines[0].strip() if self.lines else ""), textwrap.dedent("\n".join(self.lines[1:]))
        return "\n".join([(first + ("\n" + rest if rest.strip() else "")).strip()] + self.notes).strip()


class Parsed:
    """A SWIG docstring taken apart: the description, and the parameters, results and exceptions."""

    def __init__(self, text):
        self.description, self.parameters, self.results, self.raises = [], [], [], []
        current = None
        byName = {}
        for line in textwrap.dedent(text).strip("\n").splitlines():
            match = _FIELD.match(line.strip()) if not line.startswith(" ") else None
            if match is None:
                if current is not None and (line.startswith(" ") or line.strip()):
                    current.lines.append(line)
                else:
                    current = None
                    self.description.append(line)
                continue
            kind, name, rest = match.groups()
            if kind == "type":
                current = None
                byName[name] = _Entry(name, rest)
            elif kind == "param":
                current = byName.pop(name, None) or _Entry(name)
                # SWIG marks @param[out] with ", out": in Python these are results (an argout typemap).
                if current.type is not None and current.type.endswith(", out"):
                    current.type = current.type[:-len(", out")]
                    self.results.append(current)
                else:
                    self.parameters.append(current)
                current.lines.append(rest)
            elif kind == "rtype":
                current = None
                self.results.append(_Entry(None, rest))
            elif kind == "return":
                if not self.results or self.results[-1].name is not None or self.results[-1].lines:
                    self.results.append(_Entry())
                current = self.results[-1]
                current.lines.append(rest)
            else:
                # ":raises: OpenMMException if ...": the first word is the C++ exception, which reaches
                # Python as openmm.OpenMMException whatever it is.
                why = rest.partition(" ")[2]
                current = _Entry(None, _PYTHON_EXCEPTION)
                current.lines.append(why)
                self.raises.append(current)
        while self.description and not self.description[-1].strip():
            self.description.pop()

    def render(self):
        parts = ["\n".join(self.description).strip()]
        for title, entries in (("Parameters", self.parameters), ("Returns", self.results), ("Raises", self.raises)):
            if entries:
                parts.append(_section(title, entries))
        return "\n\n".join(part for part in parts if part)


def _section(title, entries):
    lines = [title, "-" * len(title)]
    for entry in entries:
        if entry.name is not None:
            lines.append(f"{entry.name} : {entry.type}" if entry.type else entry.name)
        else:
            lines.append(entry.type or "")
        description = entry.description()
        if description:
            lines.append(textwrap.indent(description, "    "))
    return "\n".join(lines)


def _overloads(text):
    """The docstring of each overload of a SWIG function (one element if it has none)."""
    blocks, current = [], []
    for line in textwrap.dedent(text).strip("\n").splitlines():
        if _OVERLOAD.match(line.strip()):
            if current:
                blocks.append("\n".join(current))
            current = []
        elif line.strip() != "|":
            current.append(line)
    blocks.append("\n".join(current))
    return [block for block in blocks if block.strip()] or [""]


def numpyStyle(text):
    """A SWIG -doxygen docstring in numpy style (each overload in turn, if there are several)."""
    if not text:
        return text
    return "\n\n".join(Parsed(block).render() for block in _overloads(text))


# ------------------------------------------------------------------------------------------------
# The Python-only notes
# ------------------------------------------------------------------------------------------------

def unitName(value):
    """The symbol of an openmm.unit Unit as the docstrings write it ("K", "1/ps", "kJ/mol")."""
    symbol = value.get_symbol()
    return "1" + symbol if symbol.startswith("/") else symbol


def _noteArguments(parsed, parameters):
    for name, argumentUnit in parameters:
        for entry in parsed.parameters:
            if entry.name == name:
                entry.type = f"float or {QUANTITY}"
                entry.notes.append(f"(in Python also a Quantity, converted to {unitName(argumentUnit)})")


def _noteResult(parsed, resultUnit):
    note = f"(in Python a Quantity, in {unitName(resultUnit)})"
    if not parsed.results:
        parsed.results.append(_Entry(None, QUANTITY))
    for entry in parsed.results:
        entry.type = QUANTITY
        entry.notes.append(note)


def _inUnit(value, argumentUnit):
    return value.value_in_unit(argumentUnit) if unit.is_quantity(value) else value


def _acceptingQuantities(method, parameters):
    @functools.wraps(method)
    def converting(self, *args, **kwargs):
        args = list(args)
        for position, (name, argumentUnit) in enumerate(parameters):
            if position < len(args):
                args[position] = _inUnit(args[position], argumentUnit)
            elif name in kwargs:
                kwargs[name] = _inUnit(kwargs[name], argumentUnit)
        return method(self, *args, **kwargs)
    return converting


def _withQuantityArguments(key, method, overloads):
    """The method converting the Quantities QUANTITY_ARGUMENTS lists for key, with the notes added to
    each overload's parsed docstring (the method itself where it lists none)."""
    if key not in QUANTITY_ARGUMENTS:
        return method
    for parsed in overloads:
        _noteArguments(parsed, QUANTITY_ARGUMENTS[key])
    return _acceptingQuantities(method, QUANTITY_ARGUMENTS[key])


def _returningQuantity(method, resultUnit):
    @functools.wraps(method)
    def converting(self, *args, **kwargs):
        return unit.Quantity(method(self, *args, **kwargs), resultUnit)
    return converting


def _constructorSummary(className, overloads):
    """The __init__ docstring: one line per overload, its call and its first paragraph."""
    lines = []
    for parsed in overloads:
        names = ", ".join(entry.name for entry in parsed.parameters)
        summary = "\n".join(parsed.description).strip().split("\n\n")[0]
        lines.append(f"{className}({names})")
        lines.append(textwrap.indent(summary, "    "))
    lines.append("")
    lines.append(f"The parameters are described in help({className}).")
    return "\n".join(lines)


def _mergedConstructorSections(overloads):
    """The constructors' parameters and exceptions as one set of sections, for the class docstring:
    a parameter that not every overload takes is optional."""
    merged = Parsed("")
    seen = {}
    for parsed in overloads:
        for entry in parsed.parameters:
            if entry.name not in seen:
                seen[entry.name] = entry
                merged.parameters.append(entry)
        for entry in parsed.raises:
            if all(entry.description() != other.description() for other in merged.raises):
                merged.raises.append(entry)
    for entry in merged.parameters:
        if not all(entry.name in (other.name for other in parsed.parameters) for parsed in overloads):
            entry.type = f"{entry.type}, optional" if entry.type else "optional"
    return merged.render()


def applyToClasses(*classes):
    """Give the SWIG proxy classes their numpy-style docstrings, their unit conversions and the notes
    about them. Each class is done once; a method is documented in the class that defines it."""
    for cls in classes:
        if cls.__dict__.get("_openmmrigidPythonApi"):
            continue
        cls.__doc__ = Parsed(cls.__doc__ or "").render()
        for name, member in list(vars(cls).items()):
            if not inspect.isfunction(member) or member.__doc__ is None:
                continue
            if name == "__init__":
                _applyToConstructor(cls, member)
                continue
            if name.startswith("_"):
                continue
            parsed = [Parsed(block) for block in _overloads(member.__doc__)]
            key = (cls.__name__, name)
            function = _withQuantityArguments(key, member, parsed)
            if key in QUANTITY_RESULTS:
                function = _returningQuantity(member, QUANTITY_RESULTS[key])
                for block in parsed:
                    _noteResult(block, QUANTITY_RESULTS[key])
            function.__doc__ = "\n\n".join(block.render() for block in parsed)
            setattr(cls, name, function)
        cls._openmmrigidPythonApi = True


def _applyToConstructor(cls, constructor):
    overloads = [Parsed(block) for block in _overloads(constructor.__doc__)]
    function = _withQuantityArguments((cls.__name__, "__init__"), constructor, overloads)
    function.__doc__ = _constructorSummary(cls.__name__, overloads)
    cls.__init__ = function
    cls.__doc__ = cls.__doc__ + "\n\n" + _mergedConstructorSections(overloads)


def fromCpp(cppFunction, notes=None, optional=(), types=None, drop=(), description=None, pythonNotes=None):
    """The numpy-style docstring of a SWIG function, for the pure-Python function or class that wraps it.

    What the Python side changes is given here, next to the Python code that does it:
    notes maps a parameter or result name to a sentence the Python function adds to its description;
    types maps a name to the Python type, where it differs from the C++ one; the parameters in
    optional have a default in Python; those in drop are not taken in Python. description replaces
    the C++ description (a class's docstring, for its constructor's parameters), and pythonNotes is a
    paragraph added to it.
    """
    parsed = Parsed(cppFunction.__doc__ or "")
    named = {entry.name: entry for entry in parsed.parameters + parsed.results if entry.name}
    for name in set(notes or {}) | set(types or {}) | set(optional) | set(drop):
        if name not in named:
            raise ValueError(f"{cppFunction.__name__} has no parameter or result {name}")
    parsed.parameters = [entry for entry in parsed.parameters if entry.name not in drop]
    for name, note in (notes or {}).items():
        named[name].notes.append(note)
    for name, pythonType in (types or {}).items():
        named[name].type = pythonType
    for name in optional:
        named[name].type = f"{named[name].type}, optional" if named[name].type else "optional"
    if description is not None:
        parsed.description = Parsed(description).description
    if pythonNotes:
        parsed.description += [""] + textwrap.wrap(pythonNotes, 100)
    return parsed.render()


def propertyDoc(pythonType, cppGetter, note=None):
    """The docstring of a property that reads cppGetter: numpy's "type: description", the getter's
    description ("Get the x" read as "The x") and a Python-only note."""
    text = "\n".join(Parsed(cppGetter.__doc__ or "").description).strip()
    if text.startswith("Get the "):
        text = "The " + text[len("Get the "):]
    return f"{pythonType}: {text}" + (f"\n\n{note}" if note else "")
