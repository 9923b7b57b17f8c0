"""Sub-commands of the ``crfmap`` command line: each module has ``add_parser`` and ``run``."""
