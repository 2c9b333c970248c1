"""A measured robot log from Python: the shipped UR5 log replayed in memory, the agreement of the RunResult with
the log against the same figures from the files and the CLI, and the errors of bad pairs."""
import json
import os
import subprocess

import numpy as np
import pytest

import jointsim

JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint"]


def test_replay_in_memory_and_agreement_match_the_files_and_the_cli(tmp_path):
    log = jointsim.data_path("logs/ur5_kufieta2013_mov6_first30s.csv")
    exp = jointsim.data_path("experiments/ur5_measured_replay.yaml")
    result = jointsim.run_experiment(exp, {"duration": 3.0})
    a = jointsim.agreement(result, log, "current_{joint}=i_actual_{j}", joint_names=JOINTS, max_lag=0.02)
    assert [p["measured"] for p in a["pairs"]] == [f"i_actual_{j}" for j in range(1, 7)]
    assert a["t_end_s"] == pytest.approx(3.0)
    # The same run written to files and judged by the CLI: the same figures.
    out = tmp_path / "run"
    jointsim.run_experiment_file(exp, out, {"duration": 3.0})
    b = jointsim.agreement(out, log, [("current_" + n, f"i_actual_{k + 1}") for k, n in enumerate(JOINTS)],
                           max_lag=0.02)
    cli = os.environ.get("JOINTSIM_CLI", "jointsim")
    js = tmp_path / "a.json"
    subprocess.run([cli, "agreement", str(out), str(log), "--joint-names", ",".join(JOINTS), "--pair",
                    "current_{joint}=i_actual_{j}", "--max-lag", "0.02", "--json", str(js)], check=True,
                   capture_output=True)
    c = json.loads(js.read_text())
    for x, y, z in zip(a["pairs"], b["pairs"], c["pairs"]):
        for key in ("rms_percent", "correlation", "lag_s", "bias"):
            # in memory vs the CSV log (written with 9 significant digits)
            assert x[key] == pytest.approx(y[key], rel=1e-5, abs=1e-6), key
            assert y[key] == z[key], key


def test_agreement_of_columns_against_closed_forms_and_errors():
    t = np.arange(0.0, 2.0, 0.004)
    m = np.sin(3 * t)
    run = {"time": t, "p": m + 0.25}
    r = jointsim.agreement(run, {"t_s": t, "m": m}, "p=m", max_lag=0.0)
    (pair,) = r["pairs"]
    assert pair["bias"] == pytest.approx(0.25)
    assert pair["rms_percent"] == pytest.approx(100 * 0.25 / (m.max() - m.min()))
    assert pair["correlation"] == pytest.approx(1.0)
    with pytest.raises(jointsim.InputError, match="expected PREDICTED=MEASURED"):
        jointsim.agreement(run, {"t_s": t, "m": m}, "p")
    with pytest.raises(jointsim.InputError, match="give joint_names too"):
        jointsim.agreement(run, {"t_s": t, "m": m}, "p_{j}=m")
    with pytest.raises(jointsim.InputError, match="missing column 'q'"):
        jointsim.agreement(run, {"t_s": t, "m": m}, "q=m")


def test_identify_currents_writes_the_drives_file_the_cli_writes(tmp_path):
    robot = jointsim.data_path("robots/ur5_drives.yaml")
    log = jointsim.data_path("logs/ur5_kufieta2013_mov6_first30s.csv")
    out = tmp_path / "drives.yaml"
    r = jointsim.identify_currents(robot, log, out)
    assert out.read_text() == r["drives_yaml"]
    assert [j["joint"] for j in r["joints"]] == JOINTS
    assert 0.6 <= min(j["kt_scale"]["value"] for j in r["joints"])
    cli_out = tmp_path / "cli.yaml"
    cli = os.environ.get("JOINTSIM_CLI", "jointsim")
    subprocess.run([cli, "identify", "currents", str(robot), str(log), "-o", str(cli_out)], check=True,
                   capture_output=True)
    assert cli_out.read_text().split("\n", 3)[3] == out.read_text().split("\n", 3)[3]  # after the paths' lines
    # The calibrated twin runs from Python with the new file.
    res = jointsim.run_experiment(jointsim.data_path("experiments/ur5_measured_replay.yaml"),
                                  {"duration": 0.5, "robot": str(out)})
    assert res.summary["status"] == "ok"
    with pytest.raises(jointsim.InputError, match="missing column 'amps_1'"):
        jointsim.identify_currents(robot, log, current="amps_{j}")


def test_identify_currents_refined_against_the_full_twin(tmp_path):
    # The first 15 s, one refinement iteration (6 replays of 15 s): the twin's RMS may only go down.
    robot = jointsim.data_path("robots/ur5_drives.yaml")
    log = jointsim.data_path("logs/ur5_kufieta2013_mov6_first30s.csv")
    replay = jointsim.data_path("experiments/ur5_measured_replay.yaml")
    r = jointsim.identify_currents(robot, log, tmp_path / "refined.yaml", t_end=15.0, refine=replay,
                                   refine_set=["duration=15"], refine_iterations=1)
    assert r["refinement_replays"] >= 3
    for j in r["joints"]:
        ref = j["refinement"]
        assert ref["twin_rms_percent_after"] <= ref["twin_rms_percent_before"]
        assert 0.6 - 1e-9 <= j["kt_scale"]["value"] <= 1.4 + 1e-9
    assert "Refined against the full twin" in (tmp_path / "refined.yaml").read_text()
    with pytest.raises(jointsim.InputError):
        jointsim.identify_currents(robot, log, refine=tmp_path / "missing.yaml")
