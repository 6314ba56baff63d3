#!/usr/bin/env python3
"""Writes docs/python.md: python/guide.md (how to build, import and use the
module, examples, benchmark figures) followed by the API reference generated
from the module's docstrings.

    PYTHONPATH=build/python python3 python/tools/python_docs.py          # write docs/python.md
    PYTHONPATH=build/python python3 python/tools/python_docs.py --check  # exit 1 when it differs
"""
import argparse
import inspect
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def signature_and_doc(obj, name):
    """pybind11 puts 'name(args) -> result' on the first docstring line."""
    doc = inspect.getdoc(obj) or ""
    lines = doc.splitlines()
    sigs, rest = [], []
    for line in lines:
        if line.startswith(name + "(") and not rest:
            sigs.append(line)
        elif line.startswith("Overloaded function.") or (line[:2].isdigit() and ". " + name + "(" in line):
            continue
        else:
            rest.append(line)
    return sigs, "\n".join(rest).strip()


def clean(sig):
    # Default objects print with their address: name their type instead, so the page is reproducible.
    sig = sig.replace("lodestone.", "").replace("numpy.ndarray[numpy.float64]", "ndarray")
    return re.sub(r"<(\w+) object at 0x[0-9a-f]+>", r"\1()", sig)


def document_routine(out, obj, name, level):
    sigs, doc = signature_and_doc(obj, name)
    for s in sigs or [name + "(...)"]:
        out.append(f"{'#' * level} `{clean(s)}`\n")
    if doc:
        out.append(doc + "\n")


def document_class(out, cls, name):
    out.append(f"### class `{name}`\n")
    doc = inspect.getdoc(cls)
    if doc:
        out.append(doc + "\n")
    if issubclass(cls, BaseException):
        return
    if hasattr(cls, "__members__"):  # an enum: its values are listed in its docstring
        return
    members = []
    for key, value in cls.__dict__.items():
        if key.startswith("_") and key not in ("__init__", "__call__", "__len__"):
            continue
        members.append((key, value))
    for key, value in members:
        if isinstance(value, property):
            doc = inspect.getdoc(value) or ""
            writable = value.fset is not None
            out.append(f"- `{key}`{' (settable)' if writable else ''}: {doc}".rstrip(": ") + "\n")
        elif key == "__members__":
            continue
        elif hasattr(value, "__name__") and callable(value) or isinstance(value, staticmethod):
            target = value.__func__ if isinstance(value, staticmethod) else value
            sigs, doc = signature_and_doc(target, key)
            sig = clean(sigs[0]) if sigs else key + "(...)"
            if key == "__init__" and not sigs:
                continue  # no constructor from Python (made by factories)
            if key == "__init__":
                sig = sig.replace("__init__(self: " + name + ", ", name + "(").replace("__init__(self: " + name + ")", name + "()")
            out.append(f"- `{sig}`" + (f": {doc}" if doc else "") + "\n")
        elif type(value).__name__ == name and hasattr(cls, "__members__"):
            continue
    if hasattr(cls, "__members__"):
        out.append("Values: " + ", ".join(f"`{k}`" for k in cls.__members__) + ".\n")
    out.append("")


def reference():
    import lodestone
    out = ["## API reference\n", "Generated from the module's docstrings by python/tools/python_docs.py.\n",
           "### Module\n", inspect.getdoc(lodestone) + "\n"]
    for name, value in lodestone.__dict__.items():
        if name.startswith("_"):
            continue
        if inspect.isclass(value):
            document_class(out, value, name)
        elif callable(value):
            document_routine(out, value, name, 3)
    return "\n".join(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare with docs/python.md instead of writing it")
    args = parser.parse_args()
    text = (ROOT / "python" / "guide.md").read_text() + "\n" + reference()
    target = ROOT / "docs" / "python.md"
    if args.check:
        if target.read_text() != text:
            print("docs/python.md differs from the docstrings; regenerate it with python/tools/python_docs.py",
                  file=sys.stderr)
            return 1
        return 0
    target.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
