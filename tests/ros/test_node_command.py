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


@pytest.mark.parametrize("argv, preset, margin", [
    ([], "default", "own"),  # the default preset, its own margin
    (["--preset", "thesis"], "thesis", None),
    (["--preset", "thesis", "--margin", "3"], "thesis", 3),
    (["--preset", "certainty"], "certainty", 5),
    (["--margin", "-1"], "default", None),
])
def test_map_mode_runs_the_preset_asked_for(argv, preset, margin):
    from crfmap.cli import build_parser
    from crfmap.commands.node import make_node
    from crfmap.crf.presets import DEFAULT_PRESET, PRESETS
    from crfmap.mapping.online import OnlineMapper

    assert {"certainty", "thesis", DEFAULT_PRESET} <= set(PRESETS)  # the cases above
    preset = DEFAULT_PRESET if preset == "default" else preset
    margin = PRESETS[preset].margin if margin == "own" else margin
    node = make_node(build_parser().parse_args(["node", "map", *argv]))
    mapper = OnlineMapper.for_sensor((0, 0, 1, 1), 0.1, -1.0, 0.1, 21, 0.05, 5.0, **node.mapper_options)
    assert mapper.preset.name == preset and mapper.margin == margin


def test_an_unknown_preset_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["node", "map", "--preset", "nonesuch"])
    err = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and "invalid choice: 'nonesuch'" in err and "certainty" in err and "\n" not in err
