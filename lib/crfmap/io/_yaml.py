"""The small YAML files crfmap reads and writes: read strictly, one-line errors naming file and key; numbers
written in the shortest text that reads back to the same float.

>>> format_number(0.05), format_number(2.0), format_number(1e-07)
('0.05', '2', '1.0e-07')
"""
from __future__ import annotations

import math
import os
import stat

import yaml

from crfmap.checks import MAX_TEXT_BYTES, check_input_file
from crfmap.errors import InputError

MAX_DEPTH = 20  # nesting of lists/mappings; the files crfmap reads nest 2 deep


class _StrictLoader(yaml.SafeLoader):
    """PyYAML's safe loader without aliases ("billion laughs") and with a nesting limit: the files crfmap reads use
    neither, and refusing them keeps a small hostile file from taking minutes or gigabytes."""

    depth = 0

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise yaml.YAMLError(f"YAML aliases (*{event.anchor}) are not accepted, at line {event.start_mark.line + 1}")
        if self.check_event(yaml.SequenceStartEvent, yaml.MappingStartEvent):
            self.depth += 1
            if self.depth > MAX_DEPTH:
                raise yaml.YAMLError(f"nested more than {MAX_DEPTH} levels deep, at line "
                                     f"{self.peek_event().start_mark.line + 1}")
            try:
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1
        return super().compose_node(parent, index)


def load_text(text, source):
    """The YAML document in ``text`` (strict: no aliases, limited nesting); errors name ``source``."""
    try:
        loader = _StrictLoader(text)
        try:
            return loader.get_single_data()
        finally:
            loader.dispose()
    except RecursionError:
        raise InputError(source, "not valid YAML: nested too deeply") from None
    except (ValueError, OverflowError) as exc:  # a constructor's complaint, e.g. an impossible date
        raise InputError(source, f"not valid YAML: {exc}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).replace("\n", " ")
        raise InputError(source, f"not valid YAML{where}: {problem}") from None


def read_text_file(path, what, limit=MAX_TEXT_BYTES):
    """The UTF-8 text of a small regular file (a FIFO, device or huge file is refused)."""
    path = check_input_file(path, what)
    try:
        # non-blocking: a FIFO swapped in after the check above must not hang the open (fstat then refuses it)
        with open(os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0)), "rb") as f:
            info = os.fstat(f.fileno())
            if not stat.S_ISREG(info.st_mode):
                raise InputError(path, f"not a regular file (a device, FIFO or socket), expected {what}")
            if info.st_size > limit:
                raise InputError(path, f"{info.st_size:,} bytes is too large for {what} (at most {limit:,})")
            return f.read(limit + 1).decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(path, "not a text file (expected YAML)") from None
    except OSError as exc:
        raise InputError(path, f"cannot read: {exc.strerror or exc}") from None


def read_yaml(path, what, limit=MAX_TEXT_BYTES):
    """The YAML document in the small regular file ``path``, read strictly (a FIFO is refused unopened)."""
    return load_text(read_text_file(path, what, limit), path)


def read_mapping(path, what):
    """The YAML mapping in file ``path`` (``what`` it should hold goes into the errors)."""
    path = check_input_file(path, what)
    doc = read_yaml(path, what)  # read_text_file and load_text already turn every failure into an InputError
    if not isinstance(doc, dict):
        raise InputError(path, f"expected a YAML mapping of keys ({what}), got {type(doc).__name__}")
    return doc


def finite_number(value, source, key):
    """A finite float from a YAML value (yaml-cpp's ``as<double>`` also takes quoted numbers)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise InputError(source, f"key '{key}' must be a number, got {value!r}")
    try:
        number = float(value)
    except (ValueError, OverflowError):
        raise InputError(source, f"key '{key}' must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise InputError(source, f"key '{key}' must be finite, got {value!r}")
    return number


def format_number(value) -> str:
    """A float as YAML text that reads back to the same float (yaml-cpp's 3 digits would lose origins like -12.3456;
    the text is nav2's whenever 3 digits suffice). Exponents get a '.0' so PyYAML reads them as floats."""
    text = repr(float(value))
    if "e" in text:
        mantissa, exponent = text.split("e")
        return f"{mantissa if '.' in mantissa else mantissa + '.0'}e{exponent}"
    return text[:-2] if text.endswith(".0") else text


def write_text(path, text):
    """Write ``text`` as UTF-8 with Unix newlines (``path`` is usually an atomic temporary file)."""
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)
