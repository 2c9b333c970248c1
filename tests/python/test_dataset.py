"""HDF5 data sets of sweeps (`jointsim batch --dataset`, jointsim.write_dataset), read back with h5py and pandas and
checked against the batch's manifest and the runs' CSV logs (an independent reader of the same results)."""
import csv
import json
import math
import subprocess
import sys

import h5py
import numpy as np
import pandas as pd
import pytest

import jointsim


def _text(column):
    return column.str.decode("utf-8") if column.dtype == object else column


@pytest.fixture(scope="module")
def fault_dataset(cli, root, tmp_path_factory):
    """The 60-run UR5 fault sweep, run by the CLI with -j 2 into one HDF5 file."""
    out = tmp_path_factory.mktemp("dataset")
    h5 = out / "faults.h5"
    sweep = root / "config" / "sweeps" / "ur5_fault_dataset.yaml"
    p = subprocess.run([str(cli), "batch", str(sweep), "-j", "2", "-o", str(out / "runs"), "--dataset", str(h5)],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    return sweep, out / "runs", h5


def test_dataset_labels_shapes_and_units_match_the_manifest_and_logs(fault_dataset, tmp_path):
    sweep, runs_dir, h5 = fault_dataset
    manifest = pd.read_csv(runs_dir / "manifest.csv", keep_default_na=False, dtype=str)
    assert len(manifest) >= 50 and (manifest["status"] == "ok").all()
    with h5py.File(h5, "r") as f:
        assert f.attrs["format"] == "jointsim-dataset" and int(f.attrs["format_version"]) == 1
        assert f.attrs["sweep"] == "ur5_fault_dataset" and int(f.attrs["runs"]) == len(manifest)
        labels = pd.DataFrame(f["labels"][()])
        for c in ("run", "status", "fault_type", "fault_joint", "design"):
            labels[c] = _text(labels[c])
        # The label table: one row per run in manifest order, the manifest's label columns as typed values.
        assert list(labels["run"]) == list(manifest["run"])
        assert list(labels["status"]) == list(manifest["status"])
        assert list(labels["fault_type"]) == list(manifest["fault_type"])
        assert list(labels["fault_joint"]) == list(manifest["fault_joint"])
        assert list(labels["design"]) == list(manifest["design"])
        for (_, lab), (_, man) in zip(labels.iterrows(), manifest.iterrows()):
            if man["fault_severity"]:
                assert lab["fault_severity"] == float(man["fault_severity"])
                assert lab["fault_onset_s"] == float(man["fault_onset_s"]) and lab["fault_count"] == 1
            else:
                assert math.isnan(lab["fault_severity"]) and math.isnan(lab["fault_onset_s"])
                assert lab["fault_count"] == 0
            assert lab["seed"] == (int(man["seed"]) if man["seed"] else -1)
        counts = labels["fault_type"].value_counts()
        assert counts["gear_stiffness_scale"] == 5 and counts[""] == 30  # 2 nominal + 28 sampled
        for t in ("sensor_dropout", "sensor_stuck", "sensor_spike", "bearing_ripple"):
            assert counts[t] == 1
        assert labels.loc[labels["fault_type"] == "sensor_stuck", "fault_onset_s"].item() == 0.2
        assert (labels["design"] == "latin_hypercube").sum() == 28
        # Every run: its log column by column (shape, unit, values to the bit) and its settings.
        for _, man in manifest.iterrows():
            g = f["runs"][man["run"]]
            assert g.attrs["status"] == "ok" and g.attrs["inputs"] == man["inputs"]
            assert g.attrs["overrides"] == man["overrides"]
            # The resume stamp: each override and fault a JSON string (unambiguous), the manifest's joined by "; ".
            stamp = dict(line.split(": ", 1) for line in g.attrs["settings"].splitlines())
            parts = json.loads(stamp["overrides"]) + ["fault " + f for f in json.loads(stamp["faults"])]
            assert "; ".join(parts) == man["overrides"]
            log = runs_dir / man["output_dir"] / "ur5_excitation.csv"
            with open(log, newline="") as fh:
                header = next(csv.reader(fh))
            data = np.loadtxt(log, delimiter=",", skiprows=1)
            assert g.attrs["columns"].split(",") == [h.split("[")[0] for h in header]
            for j, h in enumerate(header):
                name, unit = h[:-1].split("[") if h.endswith("]") else (h, "")
                assert g[name].dtype == np.float64 and g[name].shape == (data.shape[0],)
                assert g[name].attrs["unit"] == unit
                np.testing.assert_array_equal(g[name][()], data[:, j])
            assert g["time"].attrs["unit"] == "s" and g["q_elbow_joint"].attrs["unit"] == "rad"
            assert g["gear_torque_elbow_joint"].attrs["unit"] == "N·m"
    # The same file from the Python API, without rewriting the manifest: the same labels.
    again = tmp_path / "again.h5"
    info = jointsim.write_dataset(sweep, again, runs_dir)
    assert info["runs"] == len(manifest) and info["runs_with_data"] == len(manifest)
    with h5py.File(again, "r") as a, h5py.File(h5, "r") as b:
        assert a["labels"][()].tobytes() == b["labels"][()].tobytes()


def test_dataset_bad_paths_write_nothing(cli, root, tmp_path):
    sweep = root / "config" / "sweeps" / "ur5_faults.yaml"
    target = tmp_path / "missing" / "set.h5"
    p = subprocess.run([str(cli), "batch", str(sweep), "-o", str(tmp_path / "runs"), "--dataset", str(target)],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert "does not exist" in p.stderr and str(tmp_path / "missing") in p.stderr
    assert not (tmp_path / "runs").exists()  # failed before any run
    with pytest.raises(ValueError, match="does not exist"):
        jointsim.write_dataset(sweep, target, tmp_path / "runs")
    assert list(tmp_path.iterdir()) == []


def test_write_dataset_on_a_full_disk_raises_and_the_interpreter_exits_cleanly(tmp_path):
    """A full disk while the data set is written (a file-size limit, SIGXFSZ ignored): write_dataset raises with the
    system's reason and the interpreter goes on and exits normally. It used to raise and then die of SIGSEGV at exit
    (HDF5 closing the failed file); HDF5 now runs in a child process of its own."""
    sweep = {"sweep": {"name": "disk", "experiment": str(jointsim.data_path("experiments/msl_backlash.yaml"))},
             "runs": [{"name": "a"}, {"name": "b"}]}
    script = f"""
import resource, signal, sys
import jointsim
sweep = {sweep!r}
jointsim.run_batch(sweep, output_dir={str(tmp_path / 'runs')!r})
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (40 * 1024, resource.RLIM_INFINITY))
try:
    jointsim.write_dataset(sweep, {str(tmp_path / 'set.h5')!r}, {str(tmp_path / 'runs')!r})
except Exception as e:
    print('raised:', type(e).__name__, e)
    sys.exit(0)
print('no error')
sys.exit(3)
"""
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, (p.returncode, p.stdout, p.stderr)
    assert "raised:" in p.stdout and "File too large" in p.stdout, p.stdout
    assert not (tmp_path / "set.h5").exists()
    assert [f.name for f in tmp_path.iterdir() if ".tmp." in f.name] == []
