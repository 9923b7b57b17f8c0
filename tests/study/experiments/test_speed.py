"""Notebook 09's helper: the rows, captions and figures for given benchmark records, exactly."""
from crfstudy.experiments import speed as tables


def fast(size, threads, mcells, dtype="float32"):
    return {"method": "crfmap-fast", "size": size, "threads": threads, "dtype": dtype, "mcells_per_second": mcells}


def test_pick_matches_every_field_given():
    records = [fast(256, 1, 10.0), fast(256, 2, 18.0), fast(256, 2, 9.0, "float64")]
    assert tables.pick(records, "crfmap-fast", threads=2, dtype="float32") == [records[1]]
    assert tables.pick(records, "numpy-baseline") == []


def test_external_rows_relate_pgmax_to_crfmap_on_one_thread_and_keep_notes():
    records = [fast(256, 1, 100.0),
               {"method": "pgmax-bp", "size": 256, "version": "0.6.1", "mcells_per_second": 2.5,
                "max_belief_difference": 1e-6, "crfmap_float32_vs_float64": 2e-7},
               {"method": "pymaxflow-map", "size": 128, "version": "1.3", "grid": "4-connected", "seconds": 0.01234,
                "agreement_with_lbp": 0.987, "energy_map": 1234.5, "energy_lbp_labels": 1240.0},
               {"method": "pgmax-bp", "size": None, "note": "PGMax not installed"}]
    rows = tables.external_rows(records)
    assert rows[0] == ["PGMax 0.6.1 LBP (flooding)", "256^2", 2.5, 0.025, None,
                       "max belief difference 1.0e-06 (crfmap float32 vs float64: 2.0e-07)", ""]
    assert rows[1][:5] == ["PyMaxflow 1.3 graph-cut MAP, 4-connected grid", "128^2", None, None, 0.012]
    assert rows[1][5].startswith("98.7 % of cells as LBP's labels; energy 1234 (MAP)")
    assert rows[2] == ["pgmax-bp", "", None, None, None, None, "PGMax not installed"]


def test_goals_rows_in_order_with_their_goals():
    records = [
        {"method": "infer-vs-kernel", "size": 1024, "threads": 2, "iterations_per_call": 10, "ratio": 0.91, "goal": 0.8},
        {"method": "infer-vs-kernel", "size": 512, "threads": 2, "iterations_per_call": 10, "ratio": 0.85, "goal": 0.8},
        {"method": "kernel-vs-bound", "size": 512, "threads": 1, "goal_ratio": None, "ratio_to_bound": 0.5,
         "goal_mcells_per_second": 300, "kernel_mcells_per_second": 321.6},
        {"method": "start-cold", "seconds": None},
        {"method": "start-env", "seconds": 1.2, "minus_warm_seconds": 0.04},
        {"method": "converge-start", "size": 4096, "start": "uniform", "seconds_to_converge": None, "note": "skipped"},
        {"method": "preset-converge", "map": "intel", "shape": [741, 795], "preset": "certainty", "iterations": 80,
         "seconds": 0.1234, "goal_seconds": 0.2685},
        {"method": "preset-converge", "map": "aces", "seconds": None, "note": "skipped: aces missing"},
    ]
    rows = tables.goals_rows(records, start_goal=1.0)
    assert [r[1] for r in rows[:2]] == ["512^2", "1024^2"]  # by size
    assert rows[0] == ["infer() end to end / kernel, float32, 2 threads, 10 it. per call", "512^2", 0.85, ">= 0.8"]
    assert rows[2] == ["kernel, float32, 1 thread [Mcell/s]", "512^2", 322, ">= 300"]
    assert rows[3] == ["crfmap infer, first call with an empty cache [s]", "512^2", None, "not timed here: `make bench`"]
    assert rows[4] == ["crfmap infer: environment's cache minus warm [s]", "512^2", 0.0, "<= 1"]
    assert rows[5] == ["converge, uniform start", "4096^2", None, "skipped"]
    assert rows[6] == ["default preset (certainty) to convergence, intel, 80 it., float64 [s]", "741x795", 0.123,
                       "<= 0.269 (5 NumPy-baseline it.)"]
    assert rows[7] == ["default preset to convergence, aces", "", None, "skipped: aces missing"]


def test_goals_rows_give_the_empty_cache_first_call_against_its_goal():
    records = [{"method": "start-cold", "seconds": 18.04, "minus_warm_seconds": 17.2, "goal_seconds": 20.0}]
    rows = tables.goals_rows(records, start_goal=2.0)
    assert rows == [["crfmap infer, first call with an empty cache [s]", "512^2", 18.0, "<= 20"],
                    ["crfmap infer: empty cache minus warm [s]", "512^2", 17.2, "(compiling)"]]


def test_throughput_rows_pick_the_reported_sizes_and_relate_to_baseline_and_bound():
    records = [fast(s, 1, 10.0 * s / 128) for s in (128, 256, 512, 1024, 2048, 4096)]
    records += [{"method": "numpy-baseline", "size": s, "mcells_per_second": 5.0} for s in (128, 256, 512, 1024, 2048, 4096)]
    records += [{"method": "crfmap-converge", "size": 512, "iterations": 40, "seconds_to_converge": 0.12345},
                {"method": "memory", "size": 1024, "bytes_per_cell": 12.34}]
    series = [("crfmap-fast", dict(threads=1), "crfmap, 1 thread", "C0-s")]
    rows = tables.throughput_rows(records, series, smallest=256, bound=100.0)
    assert [r[1] for r in rows[:4]] == ["256^2", "512^2", "2048^2", "4096^2"]
    assert rows[0] == ["crfmap, 1 thread", "256^2", 20.0, 4.0, 0.2, "not reported"]
    assert rows[4] == ["time to converge (<1e-4), 40 it.", "512^2", 0.123, None, None, "not reported"]
    assert rows[5] == ["peak memory of infer(), bytes per cell", "1024^2", 12.3, None, None, "not reported"]


def test_a_goal_row_of_the_kernel_is_followed_by_its_division_ceiling():
    records = [{"method": "kernel-vs-bound", "size": 512, "threads": 1, "goal_ratio": None, "ratio_to_bound": 0.5,
                "goal_mcells_per_second": 1000, "kernel_mcells_per_second": 417.2,
                "division_ceiling_mcells_per_second": 905.6},
               {"method": "kernel-vs-bound", "size": 256, "threads": 1, "goal_ratio": None, "ratio_to_bound": 0.5,
                "goal_mcells_per_second": None, "kernel_mcells_per_second": 400.0,
                "division_ceiling_mcells_per_second": 905.6}]  # no goal at this size: no row
    rows = tables.goals_rows(records, start_goal=1.0)
    assert rows[:2] == [["kernel, float32, 1 thread [Mcell/s]", "512^2", 417, ">= 1000"],
                        ["division ceiling, float32, 1 thread: the kernel's rate if it only did its 4 divisions "
                         "a cell [Mcell/s]", "512^2", 906, "(information)"]]
    assert len([r for r in rows if r[0].startswith("division ceiling")]) == 1


def test_the_thesis_tables_convergence_rows_are_information_not_goals():
    records = [{"method": "converge-start", "size": 4096, "start": "uniform", "seconds_to_converge": 2.18,
                "iterations": 817, "threads": 2, "runs": 1, "first_run_seconds": 2.2}]
    rows = tables.goals_rows(records, start_goal=1.0)
    assert rows[0] == ["converge, uniform start, 817 it., 2 threads, best of 1 [s]", "4096^2", 2.18,
                       "(information: the thesis's table)"]
    from crfstudy.repro.paper import missed_goals
    assert missed_goals(["measurement", "grid", "value", "goal"], rows) == "none"


def converge(method, size, iterations, seconds, difference=0.0):
    return {"method": method, "size": size, "iterations": iterations, "seconds_to_converge": seconds,
            "max_belief_difference_vs_exact": difference}


def test_benchmark_sizes_are_the_quick_ones_the_given_ones_or_the_full_sweep():
    from crfstudy.bench.common import QUICK_SIZES, SIZES

    assert tables.benchmark_sizes([256, 512], quick=True) == list(QUICK_SIZES)
    assert tables.benchmark_sizes([256, 512], quick=False) == [256, 512]
    assert tables.benchmark_sizes(None, quick=False) == list(SIZES)


def test_settings_text_says_what_the_reproduction_leaves_out():
    text = tables.settings_text(False, [256, 1024], 3, 5e7, 1, 256, 6, 1e-6, 64, cold=False, peers=False,
                                preset_maps=["intel"], converge_start_size=2048)
    assert text.startswith("reproduction settings, lighter than `make bench`: grids up to 1024^2, medians of 3 "
                           "repeats of 5e+07 cell updates, best of 1 convergence run(s)")
    assert ", no empty-cache compilation" in text and ", no published-peer or ROS node rows" in text
    assert text.endswith("convergence on intel only, the thesis table's on 2048^2")
    full = tables.settings_text(False, [256], 5, 2e8, 2, 512, 36, 1e-7, 256, cold=True, peers=True,
                                preset_maps=["intel", "aces"], converge_start_size=4096)
    assert "no empty-cache" not in full and "no published-peer" not in full and "intel, aces only" in full
    assert tables.settings_text(True, [128], 3, 5e7, 1, 256, 6, 1e-6, 64, False, False, ["intel"], 2048) == \
        "quick settings (tests and CI)"


def test_converge_lines_by_size_then_method():
    records = [converge("crfmap-converge", 512, 40, 0.5), converge("crfmap-converge-exact", 256, 30, 0.25),
               converge("crfmap-converge", 256, 31, 0.125, 2e-6), {"method": "crfmap-fast", "size": 256}]
    lines = tables.converge_lines(records).splitlines()
    assert [line.split()[:2] for line in lines] == [["256^2", "crfmap-converge"], ["256^2", "crfmap-converge-exact"],
                                                    ["512^2", "crfmap-converge"]]
    assert lines[0].endswith("31 iterations 0.125 s  max belief difference vs exact 2.0e-06")


def test_speed_caption_names_the_bandwidth_bound_and_a_reduced_sweep():
    caption = tables.speed_caption([256, 1024], 2, {"gbytes_per_second": 12.34}, 321.0, "quick settings")
    assert "2 threads, measured bandwidth 12.3 GB/s, one-pass bound 321 Mcell/s in float32" in caption
    assert "Reduced sweep (grids up to 1024^2); the full sweep to 8192^2 is `make bench`." in caption
    assert caption.endswith(" This run: quick settings.")
    assert "Reduced sweep" not in tables.speed_caption([8192], 2, {"gbytes_per_second": 1.0}, 1.0, "x")


def test_the_figures_draw_every_series_measured():
    import matplotlib.pyplot as plt

    records = [fast(s, 1, 10.0 * s) for s in (256, 128)] + [{"method": "numpy-baseline", "size": 128,
                                                             "mcells_per_second": 5.0}]
    series = [("numpy-baseline", {}, "baseline", "k-o"), ("crfmap-fast", dict(threads=1), "fast", "C0-s")]
    fig = tables.throughput_figure(records, series, bound=300.0, top=2)
    (ax,) = fig.axes
    assert [line.get_label() for line in ax.lines] == ["baseline", "fast", "one-pass bound, 2 threads (300)"]
    assert list(ax.lines[1].get_xdata()) == [128 ** 2, 256 ** 2]  # by size
    plt.close(fig)
    fig = tables.converge_figure([converge("crfmap-converge", 256, 30, 0.25), converge("crfmap-converge", 128, 9, 0.1)])
    (ax,) = fig.axes
    assert [line.get_label() for line in ax.lines] == ["fast, frozen tiles (default)"]  # unmeasured kinds left out
    assert ax.get_xscale() == ax.get_yscale() == "log"
    plt.close(fig)


def test_goals_figure_has_its_three_panels():
    import matplotlib.pyplot as plt

    records = [{"method": "infer-vs-kernel", "size": 512, "threads": 2, "kernel_mcells_per_second": 400.0,
                "infer_mcells_per_second": 360.0, "ratio": 0.9, "goal": 0.8},
               {"method": "start-warm", "seconds": 1.5}, converge("crfmap-converge", 256, 30, 0.25)]
    fig = tables.goals_figure(records, top=2, numba_threads=2)
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == ["infer() end to end vs its kernel (goal >= 0.8x)", "First run (compiling) vs warm start",
                      "Convergence against size"]
    plt.close(fig)


def test_slowest_cells_reads_the_notebooks_of_the_last_reproduction(tmp_path, monkeypatch):
    import json

    from crfstudy import paths

    (tmp_path / "notebooks").mkdir()
    cells = [{"cell_type": "code", "metadata": {"papermill": {"duration": d}}, "source": [f"step_{d:g}()\n"]}
             for d in (1.0, 7.0)]
    (tmp_path / "notebooks" / "05_x.ipynb").write_text(json.dumps({"cells": cells, "metadata": {}}))
    monkeypatch.setattr(paths, "OUT", tmp_path)
    assert tables.slowest_cells(n=1).splitlines()[2] == "| 05_x | 1 | 7.0 | `step_7()` |"
