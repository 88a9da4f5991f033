"""sysid.family and sysid.read_family on the generated Par2-like family
(data/family: a flexible arm whose modes move with payload and stop position):
the same modes, nominal and bound as `sysid family`, from models identified in
Python."""

import csv
import json

import numpy as np
import pytest

import sysid


@pytest.fixture(scope="module")
def family_dir(data_dir):
    path = data_dir / "family"
    if not (path / "manifest.csv").exists():
        pytest.skip("the family logs (data/family) are not built")
    return path


def manifest_rows(family_dir):
    with open(family_dir / "manifest.csv", newline="") as f:
        return list(csv.DictReader(f))


def identify(family_dir, rows):
    models, data = [], []
    for row in rows:
        u, y, Ts = sysid.read_log(family_dir / row["log"], inputs=["u"], outputs=["y"])
        models.append(sysid.n4sid(u, y, Ts, order=8))
        data.append((u, y))
    return models, data


def test_family_matches_the_program(family_dir, sysid_cli, tmp_path):
    rows = manifest_rows(family_dir)[:6]
    manifest = tmp_path / "manifest.csv"
    with open(manifest, "w") as f:
        f.write("log,payload_kg,stop_position\n")
        for row in rows:
            f.write(f"{family_dir / row['log']},{row['payload_kg']},{row['stop_position']}\n")
    cli_out = tmp_path / "cli.json"
    sysid_cli("family", manifest, "--inputs", "u", "--outputs", "y", "--method", "n4sid", "--order", "8", "--out", cli_out)
    cli = json.loads(cli_out.read_text())

    models, data = identify(family_dir, rows)
    conditions = {"payload_kg": [float(r["payload_kg"]) for r in rows], "stop_position": [r["stop_position"] for r in rows]}
    py_out = tmp_path / "py.json"
    fam = sysid.family(models, data=data, conditions=conditions, out=py_out)

    assert fam["nominal"]["member"] == cli["nominal"]["member"]
    assert isinstance(fam["nominal"]["model"], sysid.Model)
    assert len(fam["modes"]) == len(cli["modes"]) == 3
    for mine, theirs in zip(fam["modes"], cli["modes"]):
        np.testing.assert_allclose(mine["freq_hz"], theirs["freq_hz"], rtol=1e-9)
    np.testing.assert_allclose(fam["uncertainty"]["bound"], cli["uncertainty"]["bound"], rtol=1e-9)
    weight = fam["uncertainty"]["weight"]
    assert isinstance(weight, sysid.Model)
    # The weight covers the bound at every listed frequency.
    f = np.asarray(fam["uncertainty"]["frequency_hz"])
    z = np.exp(2j * np.pi * f * weight.Ts)
    gain = np.array([abs((weight.C @ np.linalg.solve(zk * np.eye(weight.A.shape[0]) - weight.A, weight.B) + weight.D)[0, 0])
                     for zk in z])
    assert np.all(gain >= np.asarray(fam["uncertainty"]["bound"]) * (1 - 1e-9))
    # Conditions keep their kind: numbers as numbers, labels as strings.
    assert fam["members"][0]["conditions"] == {"payload_kg": 0.0, "stop_position": rows[0]["stop_position"]}

    back = sysid.read_family(py_out)
    assert back["nominal"]["member"] == fam["nominal"]["member"]
    assert back["members"][2]["model"].to_json() == models[2].to_json()


def test_family_refuses_mismatched_conditions(family_dir):
    models, _ = identify(family_dir, manifest_rows(family_dir)[:2])
    with pytest.raises(ValueError, match="one value per model"):
        sysid.family(models, conditions={"payload_kg": [0.0]})
    with pytest.raises(ValueError):
        sysid.family(models, uncertainty="relative")


def test_family_of_time_series_compares_the_noise_models(data_dir, tmp_path):
    """AR models of disturbance records (the Par2 GW log cut in three): the family
    compares their unit-noise innovation forms, as `sysid family --method ar` does."""
    _, y, Ts = sysid.read_log(data_dir / "par2_gw.csv", outputs=["y"])
    parts = np.array_split(y, 3)
    models = [sysid.arma(part, Ts, na=4, nc=4) for part in parts]
    fam = sysid.family(models, data=[(None, part) for part in parts], conditions={"segment": [1, 2, 3]})
    freqs = sorted(m["spread"]["freq_hz"]["mean"] for m in fam["modes"])
    assert abs(freqs[0] - 25.9) < 0.5  # GW's lightly damped mode, in every segment
    assert all(f is not None for f in fam["modes"][0]["freq_hz"])
    assert fam["uncertainty"]["weight"].B.shape[1] == 1
    assert all(0.0 < m["fit_percent"][0] <= 100.0 for m in fam["members"])
