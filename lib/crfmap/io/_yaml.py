"""The small YAML files crfmap reads and writes (map_server map YAML, ``.npy`` sidecars).

Reading is strict, with one-line errors naming the file and the key; numbers are written
in the shortest text that reads back to the same float. Private to the package: the
interfaces are :mod:`crfmap.io.map_server` and :mod:`crfmap.io.npy_grid`.

>>> format_number(0.05), format_number(2.0), format_number(1e-07)
('0.05', '2', '1.0e-07')
"""
from __future__ import annotations

import math
from pathlib import Path

import yaml

from crfmap.errors import InputError


def read_mapping(path, what):
    """The YAML mapping in file ``path`` (``what`` it should hold goes into the errors)."""
    path = Path(path)
    if not path.exists():
        raise InputError(path, f"{what} not found")
    if path.is_dir():
        raise InputError(path, f"is a folder, expected {what}")
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InputError(path, "not a text file (expected YAML)") from None
    except OSError as exc:
        raise InputError(path, f"cannot read: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).replace("\n", " ")
        raise InputError(path, f"not valid YAML{where}: {problem}") from None
    if not isinstance(doc, dict):
        raise InputError(path, f"expected a YAML mapping of keys ({what}), got {type(doc).__name__}")
    return doc


def finite_number(value, source, key):
    """A finite float from a YAML value (yaml-cpp's ``as<double>`` also takes quoted numbers)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise InputError(source, f"key '{key}' must be a number, got {value!r}")
    try:
        number = float(value)
    except ValueError:
        raise InputError(source, f"key '{key}' must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise InputError(source, f"key '{key}' must be finite, got {value!r}")
    return number


def format_number(value) -> str:
    """A float as YAML text that reads back to the same float.

    yaml-cpp (nav2) prints ``0`` and ``0.05``; it uses 3 significant digits, which loses
    origins like -12.3456 -- we print the shortest exact form instead (same text whenever
    3 digits suffice). Exponents get a '.0' so PyYAML reads them as floats too.
    """
    text = repr(float(value))
    if "e" in text:
        mantissa, exponent = text.split("e")
        return f"{mantissa if '.' in mantissa else mantissa + '.0'}e{exponent}"
    return text[:-2] if text.endswith(".0") else text


def write_text(path, text):
    """Write ``text`` as UTF-8 with Unix newlines (``path`` is usually an atomic temporary file)."""
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)
