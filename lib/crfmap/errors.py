"""Errors crfmap raises for bad input.

Every error names the input (a file, an argument, an array) and what is wrong
with it, so that the command line can print it as one line and exit with 2.
"""


class CrfmapError(Exception):
    """Base class of the errors crfmap raises on purpose."""


class InputError(CrfmapError, ValueError):
    """An input (file, array, argument) is missing or malformed.

    The message starts with the input's name, e.g. ``"map.yaml: missing key 'resolution'"``.
    """

    def __init__(self, source, problem):
        self.source = str(source)
        self.problem = str(problem)
        super().__init__(f"{self.source}: {self.problem}")


class DataMissingError(InputError):
    """A public data file is not where crfmap looks for it; the message says what to download."""
