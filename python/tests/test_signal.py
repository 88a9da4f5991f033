"""Excitation design and the pre-flight check from Python equal `sysid excite` and
`sysid check`."""

import numpy as np
import pytest

import sysid


def read_csv(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def test_excitation_signals_equal_sysid_excite(sysid_cli, tmp_path):
    sysid_cli("excite", "--signal", "chirp", "--fs", "2000", "--band", "0:100", "--samples", "4000", "--out", tmp_path / "c.csv")
    np.testing.assert_allclose(sysid.chirp(2000.0, 0.0, 100.0, 2.0), read_csv(tmp_path / "c.csv")["u"], rtol=1e-12, atol=1e-15)
    sysid_cli("excite", "--signal", "multisine", "--fs", "2000", "--band", "1:100", "--samples", "4096", "--seed", "7",
              "--out", tmp_path / "m.csv")
    x = sysid.multisine(2000.0, 1.0, 100.0, 4096, seed=7)
    assert x.shape == (4096, 1)
    assert np.sqrt(np.mean(x ** 2)) == pytest.approx(1.0, rel=1e-12)  # unit RMS over the period
    np.testing.assert_allclose(x[:, 0] / np.abs(x).max(), read_csv(tmp_path / "m.csv")["u"], rtol=1e-12, atol=1e-15)
    sysid_cli("excite", "--signal", "prbs", "--fs", "1000", "--samples", "1023", "--clock-divider", "1",
              "--out", tmp_path / "p.csv")
    np.testing.assert_array_equal(sysid.prbs(10, 1023), read_csv(tmp_path / "p.csv")["u"])
    with pytest.raises(ValueError):
        sysid.multisine(2000.0, 100.0, 1500.0, 4096)


def test_check_finds_what_sysid_check_prints(data_dir, sysid_cli):
    u, y, Ts = sysid.read_log(str(data_dir / "par2_gu.csv"), ["u"], ["y"])
    time = read_csv(data_dir / "par2_gu.csv")["t"]
    result = sysid.check(u, y, Ts, time=time, inputs=["u"], outputs=["y"])
    printed = sysid_cli("check", data_dir / "par2_gu.csv", "--inputs", "u", "--outputs", "y").stdout
    assert result["report"] in printed
    assert result["inputs"][0]["excitation_order"] >= 10
    assert result["samples"] == len(y)
    # an input that excites one frequency cannot identify more than two states, and the check says so
    t = np.arange(4000) * Ts
    sine = np.sin(2 * np.pi * 20 * t)
    rng = np.random.default_rng(1)
    narrow = sysid.check(sine, np.roll(sine, 3) + 0.01 * rng.standard_normal(4000), Ts)
    assert narrow["inputs"][0]["excitation_order"] == 2
    assert any("excit" in finding for finding in narrow["findings"])
