"""Every identification method from Python gives the very model the command line
writes for the same log and options (the same library, the same model file)."""

import json

import numpy as np
import pytest

import sysid


def without_data(text):
    """A model or Markov file's content without the keys only the command line knows
    (the log's file name and the validation label)."""
    content = json.loads(text)
    for key in ("data", "validation"):
        content.get("provenance", {}).pop(key, None)
    return content


@pytest.fixture(scope="module")
def par2(data_dir):
    return sysid.read_log(str(data_dir / "par2_gu.csv"), ["u"], ["y"])


@pytest.fixture(scope="module")
def par2_gw(data_dir):
    return sysid.read_log(str(data_dir / "par2_gw.csv"), [], ["y"])


def cli_model(sysid_cli, tmp_path, verb, log, *options):
    path = tmp_path / f"{verb}.json"
    sysid_cli(verb, log, *options, "--out", path)
    return path.read_text()


@pytest.mark.parametrize("method", ["n4sid", "moesp", "cva"])
def test_subspace_methods_equal_the_command_line(method, par2, data_dir, sysid_cli, tmp_path):
    u, y, Ts = par2
    cli = cli_model(sysid_cli, tmp_path, "n4sid", data_dir / "par2_gu.csv", "--inputs", "u", "--outputs", "y",
                    "--method", method, "--order", "10")
    with pytest.warns(RuntimeWarning):  # the Par2 chirp excites 0..100 Hz of 1 kHz: the tool says so
        model = sysid.n4sid(u, y, Ts, order=10, method=method, inputs=["u"], outputs=["y"])
    assert without_data(model.to_json()) == without_data(cli)
    assert model.provenance["method"] == method


def test_the_automatic_order_equals_the_command_line(par2, data_dir, sysid_cli, tmp_path):
    u, y, Ts = par2
    cli = cli_model(sysid_cli, tmp_path, "n4sid", data_dir / "par2_gu.csv", "--inputs", "u", "--outputs", "y")
    with pytest.warns(RuntimeWarning):
        model = sysid.n4sid(u, y, Ts, inputs=["u"], outputs=["y"])
    assert without_data(model.to_json()) == without_data(cli)
    assert model.provenance["order_rule"] == json.loads(cli)["provenance"]["order_rule"]


def test_a_refined_subspace_model_equals_the_command_line(par2, data_dir, sysid_cli, tmp_path):
    # A horizon other than the automatic one: the poles are refined on the simulation
    # error (issue 34 item 3), the same way from both; refine="never" keeps them.
    u, y, Ts = par2
    cli = cli_model(sysid_cli, tmp_path, "n4sid", data_dir / "par2_gu.csv", "--inputs", "u", "--outputs", "y",
                    "--method", "moesp", "--order", "10", "--horizon", "30")
    with pytest.warns(RuntimeWarning):
        model = sysid.n4sid(u, y, Ts, order=10, method="moesp", horizon=30, inputs=["u"], outputs=["y"])
    assert without_data(model.to_json()) == without_data(cli)
    refinement = model.provenance["pole_refinement"]
    assert refinement["refined"] and refinement["fit_after"] > refinement["fit_before"]
    with pytest.warns(RuntimeWarning):
        plain = sysid.n4sid(u, y, Ts, order=10, method="moesp", horizon=30, refine="never")
    assert "pole_refinement" not in plain.provenance
    with pytest.raises(ValueError):
        sysid.n4sid(u, y, Ts, order=10, refine="sometimes")


@pytest.mark.parametrize("verb, python_options, cli_options", [
    ("arx", dict(na=6, nb=6, nk=1), ["--na", "6", "--nb", "6"]),
    ("armax", dict(na=4, nb=4, nc=2), ["--na", "4", "--nb", "4", "--nc", "2"]),
    ("oe", dict(nb=4, nf=4), ["--nb", "4", "--nf", "4"]),
])
def test_polynomial_models_equal_the_command_line(verb, python_options, cli_options, par2, data_dir, sysid_cli, tmp_path):
    u, y, Ts = par2
    cli = cli_model(sysid_cli, tmp_path, verb, data_dir / "par2_gu.csv", "--inputs", "u", "--outputs", "y", *cli_options)
    model = getattr(sysid, verb)(u, y, Ts, inputs=["u"], outputs=["y"], **python_options)
    assert model.type == "polynomial"
    assert without_data(model.to_json()) == without_data(cli)


@pytest.mark.parametrize("method", ["ls", "burg", "myw"])
def test_time_series_models_equal_the_command_line(method, par2_gw, data_dir, sysid_cli, tmp_path):
    _, w, Ts = par2_gw
    cli = cli_model(sysid_cli, tmp_path, "ar", data_dir / "par2_gw.csv", "--outputs", "y", "--na", "8", "--method", method)
    model = sysid.ar(w, Ts, na=8, method=method, outputs=["y"])
    assert without_data(model.to_json()) == without_data(cli)
    arma = sysid.arma(w, Ts, na=4, nc=2, outputs=["y"])
    assert arma.extra["structure"] == "arma" and arma.inputs == []


def test_okid_era_and_lms_equal_the_command_line(par2, data_dir, sysid_cli, tmp_path):
    u, y, Ts = par2
    log = data_dir / "par2_gu.csv"
    okid_file, lms_file = tmp_path / "okid.json", tmp_path / "lms.json"
    sysid_cli("okid", log, "--inputs", "u", "--outputs", "y", "--observer-order", "30", "--out", okid_file)
    sysid_cli("lms", log, "--inputs", "u", "--outputs", "y", "--taps", "200", "--steps", "2", "--out", lms_file)
    with pytest.warns(RuntimeWarning):
        markov = sysid.okid(u, y, Ts, observer_order=30, inputs=["u"], outputs=["y"])
    np.testing.assert_array_equal(markov.h, sysid.read_markov(str(okid_file)).h)
    assert markov.h.shape == (121, 1, 1)
    with pytest.warns(RuntimeWarning):
        fir = sysid.lms(u, y, Ts, taps=200, steps=2, inputs=["u"], outputs=["y"])
    np.testing.assert_array_equal(fir.h, sysid.read_markov(str(lms_file)).h)
    era_cli = cli_model(sysid_cli, tmp_path, "era", okid_file, "--order", "10")
    model = sysid.era(sysid.read_markov(str(okid_file)), order=10)
    expected = json.loads(era_cli)
    assert np.array_equal(model.A, np.array(expected["A"])) and model.provenance["order"] == 10
    # a Markov written from Python is the command line's file
    markov.write(str(tmp_path / "again.json"))
    np.testing.assert_array_equal(sysid.read_markov(str(tmp_path / "again.json")).h, markov.h)


def test_prediction_error_failures_are_numerical_errors(par2):
    u, y, Ts = par2
    with pytest.raises(sysid.NumericalError, match="did not converge"):
        sysid.armax(u, y, Ts, na=10, nb=10, nc=10, max_iterations=1)
    model = sysid.armax(u, y, Ts, na=10, nb=10, nc=10, max_iterations=1, allow_unconverged=True)
    assert model.provenance["converged"] is False
    with pytest.raises(ValueError, match="one per input"):
        sysid.arx(u, y, Ts, na=2, nb=[2, 2])


def test_the_stabilization_diagram_equals_the_command_line(data_dir, sysid_cli, tmp_path):
    # The 8x8 example log over orders 2..40 (issue 34 item 2): the same poles and
    # marks as the command line's CSV, the same model file, and the 444 Hz column
    # that stands at the noise's level named with its reason, not counted.
    channels = [f"u{k}" for k in range(1, 9)], [f"y{k}" for k in range(1, 9)]
    u, y, Ts = sysid.read_log(str(data_dir / "avi8x8.csv"), *channels)
    table = tmp_path / "stab.csv"
    cli = cli_model(sysid_cli, tmp_path, "n4sid", data_dir / "avi8x8.csv", "--inputs", ",".join(channels[0]),
                    "--outputs", ",".join(channels[1]), "--order", "2:40", "--stabilization", table)
    diagram, model = sysid.stabilization_diagram(u, y, Ts, orders=(2, 40), inputs=channels[0], outputs=channels[1])
    assert without_data(model.to_json()) == without_data(cli)
    rows = np.loadtxt(table, delimiter=",", skiprows=1)
    header = table.read_text().splitlines()[0].split(",")
    poles = diagram["poles"]
    for name in ("order", "freq_hz", "damping", "stable_frequency", "stable_damping", "stable_shape", "mode", "level"):
        np.testing.assert_array_equal(rows[:, header.index(name)], np.asarray(poles[name], dtype=float), err_msg=name)
    assert poles["stable_shape"].dtype == bool
    assert diagram["chosen_order"] == 16 == model.A.shape[0]
    assert len(diagram["modes"]) == 8
    assert all(m["level_ratio"] > 100 and m["shape"].shape == (8,) for m in diagram["modes"])
    [noise] = diagram["noise_columns"]
    assert abs(noise["freq_hz"] - 443.8) < 1.0 and noise["level_ratio"] < 3
    assert "wandering poles'" in noise["reason"]
    # The level test off: the noise column counts, as with --min-level-ratio 0.
    everything, _ = sysid.stabilization_diagram(u, y, Ts, orders=(2, 40), min_level_ratio=0)
    assert len(everything["modes"]) == 9 and not everything["noise_columns"]


def test_the_stabilization_diagram_refuses_bad_options(par2):
    u, y, Ts = par2
    with pytest.raises(ValueError, match="orders"):
        sysid.stabilization_diagram(u, y, Ts, orders=(10, 4))
    with pytest.raises(ValueError, match="min_level_ratio"):
        sysid.stabilization_diagram(u, y, Ts, orders=(2, 20), min_level_ratio=-1)
    with pytest.raises(ValueError, match="needs the inputs"):
        sysid.stabilization_diagram(None, y, Ts, orders=(2, 20))
