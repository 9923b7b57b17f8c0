"""Errors crfmap raises for bad input: each names the input (a file, an argument, an array) and what is wrong with it,
so that the command line can print it as one line and exit with 2.
"""


MAX_MESSAGE = 400  # characters of one part of an error line (a hostile input can hold megabytes)


def one_line(text, limit=MAX_MESSAGE) -> str:
    r"""``text`` as one line of at most ``limit`` characters (newlines become spaces).

    >>> one_line("bad\nheader " + "x" * 500)[:20], len(one_line("x" * 500))
    ('bad header xxxxxxxxx', 400)
    """
    text = " ".join(str(text).split("\n")).replace("\r", " ")
    return text if len(text) <= limit else text[: limit - 5] + "[...]"


class CrfmapError(Exception):
    """Base class of the errors crfmap raises on purpose."""


class InputError(CrfmapError, ValueError):
    """An input is missing or malformed; the message starts with its name: ``"map.yaml: missing key 'resolution'"``."""

    def __init__(self, source, problem):
        self.source = one_line(source)
        self.problem = one_line(problem)
        super().__init__(f"{self.source}: {self.problem}")


class DataMissingError(InputError):
    """A public data file is not where crfmap looks for it; the message says what to download."""
