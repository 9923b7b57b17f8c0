"""`crfmap node`'s options: what cannot work is refused in one line with exit status 2, before any middleware starts."""
import importlib.util

import pytest

from crfmap.cli import main


@pytest.mark.parametrize("args, words", [
    (["map", "--bounds", "1", "1", "0", "0"], "--bounds: need XMIN < XMAX"),
    (["map", "--resolution", "0"], "--resolution"),
    (["map", "--radius", "nan"], "--radius"),
    (["map", "--margin", "-2"], "--margin"),
    (["refine", "--period", "-1"], "--period"),
    (["refine", "--backend", "rospy", "--domain", "3"], "--domain: applies to the dds backend only"),
])
def test_bad_options_are_one_line_errors(args, words, capsys):
    assert main(["node", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and words in err and err.startswith("crfmap node: error:")


@pytest.mark.skipif(importlib.util.find_spec("rclpy") is not None, reason="rclpy is installed here")
def test_a_missing_backend_is_a_one_line_error(capsys):
    assert main(["node", "refine", "--backend", "rclpy"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("crfmap node: error: --backend rclpy: rclpy is not importable") and "\n" not in err
