"""Notebook 09's tables from benchmark records: the rows for given records, exactly."""
from crfstudy.experiments import speed_tables as tables


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
