"""Read openmmrigid's docstrings, written for help() in numpy style, as reStructuredText.

The docstrings come from the C++ Doxygen (one text for both languages) and are plain text: a
formula on an indented line of its own, a list right under its lead-in line ("one of" then
"- Verlet: ..."), |u| for an absolute value. reStructuredText reads those as a block quote without
its blank lines, a list run into a paragraph, and a substitution. This extension adds the blank
lines and escapes the bars, before napoleon turns the numpy sections into fields, and after it puts
back the first words of a class constant's docstring that napoleon took for a type. It changes no
word.
"""

import re

_BULLET = re.compile(r"^(\s*)- \S")
_SECTION_RULE = re.compile(r"^\s*-{3,}\s*$")
_LITERAL = re.compile(r"(``.*?``)")


def _indent(line):
    return len(line) - len(line.lstrip())


def _escapeBars(line):
    """| outside ``literals`` is text (an absolute value), not a substitution."""
    parts = _LITERAL.split(line)
    return "".join(part if part.startswith("``") else part.replace("|", r"\|") for part in parts)


def _isSectionHeader(lines, index):
    return index + 1 < len(lines) and lines[index].strip() and _SECTION_RULE.match(lines[index + 1]) is not None


def _separateBlocks(lines):
    """Blank lines around lists and around indented lines inside a paragraph, so that each is a block."""
    result = []
    listIndent = None  # the indent of the bullets of the list being read, or None outside a list
    blockIndent = None  # the indent of the block being read that was cut out of a paragraph, or None
    definitions = False  # whether the paragraph being read is a definition list ("name : type", description)
    for index, line in enumerate(lines):
        previous = result[-1] if result else ""
        stripped = line.strip()
        bullet = _BULLET.match(line)
        if not stripped:
            listIndent = blockIndent = None
            definitions = False
            result.append(line)
            continue
        if bullet:
            indent = len(bullet.group(1))
            if listIndent is None and previous.strip():
                result.append("")  # a list starts: end the lead-in paragraph
            listIndent = indent
            result.append(line)
            continue
        if listIndent is not None:
            if _indent(line) > listIndent:
                result.append(line)  # an item's continuation
                continue
            result.append("")  # the list ends at a line back at (or left of) its bullets
            listIndent = None
            result.append(line)
            continue
        if previous.strip() and _indent(line) > _indent(previous) and (definitions or _startsParagraph(result)):
            definitions = True  # a description under its term (the term starts the paragraph, or follows one)
            result.append(line)
            continue
        if (previous.strip() and _indent(line) > _indent(previous) and not previous.rstrip().endswith("::")
                and not _inSection(lines, index)):
            # An indented line inside a paragraph (a formula): a block of its own.
            result.append("")
            blockIndent = _indent(line)
            result.append(line)
            continue
        if blockIndent is not None and _indent(line) < blockIndent:
            result.append("")  # the paragraph goes on after the block
            blockIndent = None
        result.append(line)
    return result


def _startsParagraph(result):
    """Whether the last line of `result` is the first line of its paragraph (None if there is none)."""
    if not result or not result[-1].strip():
        return None
    return len(result) == 1 or not result[-2].strip()


def _inSection(lines, index):
    """Whether line `index` is in a numpy section (Parameters, Returns, ...), where indentation is structure."""
    for earlier in range(index - 1, -1, -1):
        if _isSectionHeader(lines, earlier):
            return True
    return False


def readAsRst(app, what, name, obj, options, lines):
    if not name.startswith("openmmrigid"):
        return
    fixed = _separateBlocks([_escapeBars(line) for line in lines])
    lines[:] = fixed


def keepConstantsWhole(app, what, name, obj, options, lines):
    """After napoleon: it reads the first line of a class constant's docstring, "Velocity Verlet: kick
    dt/2, ...", as "type: text" (the form properties use: "str: The kind of rotor ..."). A constant
    (RigidBodyIntegrator.Verlet) has no such type: put the words back in front of the text."""
    if not name.startswith("openmmrigid") or what != "attribute" or not isinstance(obj, (int, float)):
        return
    types = [index for index, line in enumerate(lines) if line.startswith(":type: ")]
    if len(types) != 1:
        return
    words = lines.pop(types[0])[len(":type: "):]
    while lines and not lines[-1].strip():
        lines.pop()
    first = next((index for index, line in enumerate(lines) if line.strip()), None)
    if first is None:
        lines[:] = [words]
    else:
        lines[first] = words + ": " + lines[first]


def setup(app):
    # Before napoleon (priority 500), which reads the numpy sections.
    app.connect("autodoc-process-docstring", readAsRst, priority=400)
    app.connect("autodoc-process-docstring", keepConstantsWhole, priority=600)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
