"""Reduction, spectra, filtering, validation and diagnose from Python equal what
the command line computes on the same files."""

import json

import numpy as np
import pytest

import sysid


@pytest.fixture(scope="module")
def par2(data_dir):
    return sysid.read_log(str(data_dir / "par2_gu.csv"), ["u"], ["y"])


@pytest.fixture(scope="module")
def model_file(tmp_path_factory, data_dir, sysid_cli):
    path = tmp_path_factory.mktemp("analysis") / "model.json"
    sysid_cli("n4sid", data_dir / "par2_gu.csv", "--inputs", "u", "--outputs", "y", "--order", "10", "--out", path)
    return path


def read_csv(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def test_reduce_and_hsv_equal_the_command_line(model_file, sysid_cli, tmp_path):
    model = sysid.read_model(str(model_file))
    for python_options, cli_options in [(dict(order=4), ["--order", "4"]), (dict(max_error=0.02), ["--max-error", "0.02"]),
                                        (dict(band=(20.0, 80.0)), ["--band", "20:80"])]:
        out = tmp_path / "reduced.json"
        sysid_cli("reduce", model_file, *cli_options, "--out", out, "--force")
        reduced = sysid.reduce(model, **python_options)
        cli = json.loads(out.read_text())
        cli["provenance"].pop("source")
        assert json.loads(reduced.to_json()) == cli
    values = sysid.hsv(model)
    assert values.shape == (10,) and np.all(np.diff(values) <= 0)
    with pytest.raises(ValueError, match="exactly one"):
        sysid.reduce(model, order=2, max_error=0.1)


def test_frf_and_psd_equal_the_command_line(par2, data_dir, sysid_cli, tmp_path):
    u, y, Ts = par2
    frf_csv, psd_csv = tmp_path / "frf.csv", tmp_path / "psd.csv"
    sysid_cli("frf", data_dir / "par2_gu.csv", "--inputs", "u", "--outputs", "y", "--nfft", "2048", "--out", frf_csv)
    sysid_cli("psd", data_dir / "par2_gu.csv", "--columns", "y", "--nfft", "2048", "--out", psd_csv)
    estimate = sysid.frf(u, y, Ts, nfft=2048)
    cli = read_csv(frf_csv)
    np.testing.assert_allclose(estimate["freq_hz"], cli["f_hz"], rtol=1e-12)
    np.testing.assert_allclose(estimate["H"][:, 0, 0], cli["re_y_u"] + 1j * cli["im_y_u"], rtol=1e-12)
    np.testing.assert_allclose(estimate["coherence"][:, 0, 0], cli["coh_y_u"], rtol=1e-12)
    assert estimate["coherence"].shape == (1025, 1, 1)
    freq, psd = sysid.psd(y, Ts, nfft=2048)
    cli = read_csv(psd_csv)
    np.testing.assert_allclose(psd[:, 0], cli["psd_y"], rtol=1e-9)


def test_filter_equals_the_command_line(data_dir, sysid_cli, tmp_path):
    out = tmp_path / "filtered.csv"
    sysid_cli("filter", data_dir / "par2_gu.csv", "--columns", "y", "--lowpass", "50", "--order", "4", "--out", out)
    _, y, Ts = sysid.read_log(str(data_dir / "par2_gu.csv"), ["u"], ["y"])
    filtered = sysid.filter(y, Ts, lowpass=50.0, order=4)
    np.testing.assert_allclose(filtered[:, 0], read_csv(out)["y"], rtol=1e-9, atol=1e-12 * np.abs(y).max())
    zero_phase = sysid.filter(y, Ts, lowpass=50.0, order=4, zero_phase=True)
    assert not np.allclose(zero_phase, filtered)


def test_compare_and_resid(model_file, data_dir, sysid_cli):
    model = sysid.read_model(str(model_file))
    u, y, Ts = sysid.read_log(str(data_dir / "par2_gu_val.csv"), ["u"], ["y"])
    fit, y_hat = sysid.compare(model, u, y)
    printed = sysid_cli("compare", model_file, data_dir / "par2_gu_val.csv").stdout
    assert f"{fit[0]:.2f}" in printed or f"{fit[0]:.4g}" in printed
    np.testing.assert_allclose(sysid.fit_percent(y, y_hat), fit, rtol=1e-12)
    analysis = sysid.resid(model, u, y, max_lag=20)
    assert analysis["autocorrelation"].shape == (21, 1)
    assert analysis["residuals"].shape == y.shape
    assert isinstance(analysis["white"][0], bool) and analysis["whiteness"][0]


def test_diagnose_equals_the_command_line(data_dir, sysid_cli, tmp_path):
    case = data_dir / "concealed" / "arm_cubic_stiffness"
    report_file = tmp_path / "report.json"
    sysid_cli("diagnose", "--model", case / "nominal.json", case / "log.csv", "--json", report_file)
    nominal = sysid.read_model(str(case / "nominal.json"))
    u, y, Ts = sysid.read_log(str(case / "log.csv"), nominal.inputs, nominal.outputs)
    report, augmented = sysid.diagnose(nominal, u, y, Ts)
    cli = json.loads(report_file.read_text())
    assert [f["kind"] for f in report["findings"]] == [f["kind"] for f in cli["findings"]]
    assert report["findings"][0]["kind"] == "cubic_stiffness"
    assert report["fit_after"] == cli["fit_after"]
    assert augmented.type == "augmented"
    assert sysid.fit_percent(y, augmented.simulate(u))[0] > sysid.fit_percent(y, nominal.simulate(u))[0]
    # Every finding states its parameters' standard errors (DESIGN.md "uncertainty").
    assert set(report["findings"][0]["uncertainty"]) == set(report["findings"][0]["params"])


def test_diagnose_reads_a_velocity_output(data_dir):
    case = data_dir / "concealed" / "drive_velocity_friction"
    nominal = sysid.read_model(str(case / "nominal.json"))
    u, y, Ts = sysid.read_log(str(case / "log.csv"), nominal.inputs, nominal.outputs)
    report, augmented = sysid.diagnose(nominal, u, y, Ts, output_quantity=["velocity"])
    assert report["output_quantities"] == {"y": "velocity"}
    assert report["findings"][0]["kind"] == "coulomb_friction"
    assert abs(report["findings"][0]["params"]["level"] / 0.1 - 1.0) < 0.1
    with pytest.raises(ValueError):
        sysid.diagnose(nominal, u, y, Ts, output_quantity=["speed"])
