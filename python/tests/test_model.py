"""sysid.Model and the model files: the command line's files read and written byte
for byte, simulation as `sysid simulate`, python-control, and errors."""

import json

import numpy as np
import pytest

import sysid


@pytest.fixture(scope="module")
def par2_model(tmp_path_factory, data_dir, sysid_cli):
    path = tmp_path_factory.mktemp("model") / "par2.json"
    sysid_cli("n4sid", data_dir / "par2_gu.csv", "--inputs", "u", "--outputs", "y", "--order", "6", "--out", path)
    return path


def test_a_command_line_model_file_round_trips_byte_for_byte(par2_model, tmp_path):
    text = par2_model.read_text()
    model = sysid.read_model(str(par2_model))
    assert model.to_json() == text
    copy = tmp_path / "copy.json"
    model.write(str(copy))
    assert copy.read_bytes() == par2_model.read_bytes()
    assert sysid.model_from_json(text).to_json() == text


def test_polynomial_files_keep_their_coefficients(data_dir, sysid_cli, tmp_path):
    path = tmp_path / "armax.json"
    sysid_cli("armax", data_dir / "par2_gu.csv", "--inputs", "u", "--outputs", "y", "--na", "4", "--nb", "4", "--nc", "2",
              "--out", path)
    model = sysid.read_model(str(path))
    assert model.type == "polynomial"
    assert model.extra["structure"] == "armax"
    assert len(model.extra["A"][0]) == 5
    assert model.to_json() == path.read_text()


def test_the_model_carries_the_file_fields(par2_model):
    model = sysid.read_model(str(par2_model))
    stored = json.loads(par2_model.read_text())
    np.testing.assert_array_equal(model.A, np.array(stored["A"]))
    np.testing.assert_array_equal(model.C, np.array(stored["C"]))
    assert model.Ts == stored["Ts"]
    assert model.order == 6
    assert model.inputs == ["u"] and model.outputs == ["y"]
    assert model.provenance["method"] == "n4sid"
    assert model.K.shape == (6, 1) if model.K is not None else "K" not in stored
    assert len(model.poles()) == 6
    modes = model.modes()
    assert all(m["stable"] for m in modes)
    assert [m["freq_hz"] for m in modes] == sorted(m["freq_hz"] for m in modes)


def test_simulate_gives_what_sysid_simulate_writes(par2_model, data_dir, sysid_cli, tmp_path):
    out = tmp_path / "sim.csv"
    sysid_cli("simulate", par2_model, data_dir / "par2_gu_val.csv", "--inputs", "u", "--out", out)
    cli = np.genfromtxt(out, delimiter=",", names=True)
    model = sysid.read_model(str(par2_model))
    u, _, _ = sysid.read_log(str(data_dir / "par2_gu_val.csv"), ["u"], ["y"])
    y_hat = model.simulate(u)
    assert y_hat.shape == (len(u), 1)
    np.testing.assert_allclose(y_hat[:, 0], cli["y"], rtol=1e-12, atol=1e-12 * np.abs(cli["y"]).max())
    # 1-D input for a one-input model, and a given initial state
    np.testing.assert_array_equal(model.simulate(u[:, 0]), y_hat)
    x0 = np.ones(model.order)
    assert not np.allclose(model.simulate(u, x0=x0), y_hat)


def test_a_model_built_from_arrays_checks_its_dimensions():
    A = np.array([[0.9, 0.1], [0.0, 0.8]])
    model = sysid.Model(A, np.ones((2, 1)), np.ones((1, 2)), np.zeros((1, 1)), 0.01, inputs=["f"], outputs=["a"])
    assert model.inputs == ["f"] and model.type == "state-space"
    step = model.simulate(np.ones(200))
    dc = (np.ones((1, 2)) @ np.linalg.solve(np.eye(2) - A, np.ones((2, 1))))[0, 0]
    assert step[-1, 0] == pytest.approx(dc, rel=1e-9)
    with pytest.raises(ValueError, match="B must have 2 rows"):
        sysid.Model(A, np.ones((3, 1)), np.ones((1, 2)), np.zeros((1, 1)), 0.01)
    with pytest.raises(ValueError):
        model.simulate(np.ones((10, 2)))


def test_to_control_gives_the_same_system(par2_model):
    control = pytest.importorskip("control")
    model = sysid.read_model(str(par2_model))
    sys = model.to_control()
    assert isinstance(sys, control.StateSpace)
    assert sys.dt == model.Ts
    np.testing.assert_array_equal(sys.A, model.A)
    np.testing.assert_array_equal(sys.D, model.D)
    assert sys.input_labels == ["u"] and sys.output_labels == ["y"]


def test_a_bad_model_file_is_a_data_error_with_its_line(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"Ts": 0.1,\n "A": [[1]], "B": [[1]],\n "C": [[1]] "D": [[0]]}\n')
    with pytest.raises(sysid.DataError, match=r"bad.json:3:"):
        sysid.read_model(str(bad))
    assert issubclass(sysid.DataError, ValueError)


def test_write_mat_is_what_sysid_export_writes_and_scipy_reads(par2_model, sysid_cli, tmp_path):
    io = pytest.importorskip("scipy.io")
    model = sysid.read_model(str(par2_model))
    model.write_mat(str(tmp_path / "python.mat"))
    sysid_cli("export", par2_model, "--mat", tmp_path / "cli.mat")
    assert (tmp_path / "python.mat").read_bytes()[128:] == (tmp_path / "cli.mat").read_bytes()[128:]  # after the dated header
    variables = io.loadmat(str(tmp_path / "python.mat"))
    np.testing.assert_array_equal(variables["A"], model.A)
    np.testing.assert_array_equal(variables["B"], model.B)
    np.testing.assert_array_equal(variables["D"], model.D)
    assert variables["Ts"][0, 0] == model.Ts
    assert [str(name[0]) for name in variables["InputName"][:, 0]] == model.inputs
    assert [str(name[0]) for name in variables["OutputName"][:, 0]] == model.outputs
