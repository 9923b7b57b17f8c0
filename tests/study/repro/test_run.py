"""crfstudy.repro.run: the notebook runner's import of papermill."""
import subprocess
import sys

PROBE = """
import sys
from crfstudy.repro.run import import_papermill
pm = import_papermill()
import nbformat
nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("x = 1")])
nbformat.validate(nb)  # the notebook schema still checks
try:
    nbformat.validate({"cells": "not a list"})
except nbformat.ValidationError:
    print("invalid caught")
print("jsonschema" in sys.modules, sys.modules.get("rfc3987_syntax", "absent"))
"""


def test_papermill_imports_without_the_iri_parsers_and_notebooks_still_validate():
    out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == "invalid caught"
    assert out[1] == "True None"  # jsonschema loaded; rfc3987_syntax kept out (not imported)


def test_a_process_that_already_has_jsonschema_is_left_alone():
    probe = "import sys, jsonschema\nfrom crfstudy.repro.run import import_papermill\nimport_papermill()\n" \
            "print(sys.modules.get('rfc3987_syntax', 'absent') is None)"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "False"
