"""crfstudy.repro.variables: the study's own environment variables, each checked where it is read, errors name it."""
import pytest

from crfmap.errors import InputError
from crfstudy.repro import variables


def test_run_context_is_checked(monkeypatch):
    monkeypatch.setenv("CRFMAP_RUN", '{"notebook": "x/../y.ipynb"}')
    with pytest.raises(InputError, match="CRFMAP_RUN="):
        variables.run_context()


@pytest.mark.parametrize("text", ["abc", "nan", "-5", "inf"])
def test_reproduce_start_is_checked(monkeypatch, text):
    monkeypatch.setenv("CRFMAP_REPRODUCE_STARTED", text)
    with pytest.raises(InputError, match="CRFMAP_REPRODUCE_STARTED=.*expected a Unix time"):
        variables.reproduce_started()
    monkeypatch.setenv("CRFMAP_REPRODUCE_STARTED", "1796286356")
    assert variables.reproduce_started() == 1796286356.0
    monkeypatch.setenv("CRFMAP_REPRODUCE_STARTED", "")
    assert variables.reproduce_started() is None
