"""The finite-element side from Python: modes, the modal reduction `sysid reduce
--fem` writes, and the sparse frequency response `sysid frf --fem` computes."""

import json

import numpy as np
import pytest

import sysid


@pytest.fixture(scope="module")
def beam_path(data_dir):
    return data_dir / "fem" / "beam.json"


def test_modal_reduction_equals_the_command_line(beam_path, sysid_cli, tmp_path):
    out = tmp_path / "modal.json"
    sysid_cli("reduce", "--fem", beam_path, "--modes", "6", "--ts", "0.0005", "--out", out)
    fem = sysid.read_fem(str(beam_path))
    model = sysid.fem_reduce(fem, modes=6, Ts=0.0005)
    cli = json.loads(out.read_text())
    cli["provenance"].pop("source")
    assert json.loads(model.to_json()) == cli
    modes = sysid.fem_modes(fem, modes=6)
    np.testing.assert_array_equal(modes["freq_hz"], cli["provenance"]["natural_frequencies_hz"])
    assert modes["mode_shapes"].shape == (fem.dofs, 6)


def test_sparse_frf_equals_the_command_line(beam_path, sysid_cli, tmp_path):
    out = tmp_path / "frf.csv"
    sysid_cli("frf", "--fem", beam_path, "--band", "1:200", "--points", "60", "--out", out)
    cli = np.genfromtxt(out, delimiter=",", names=True)
    fem = sysid.read_fem(str(beam_path))
    response = sysid.fem_frf(fem, cli["f_hz"])
    first = f"{fem.outputs[0]}_{fem.inputs[0]}"
    np.testing.assert_allclose(response["H"][:, 0, 0], cli["re_" + first] + 1j * cli["im_" + first], rtol=1e-12)
    assert response["H"].shape == (60, len(fem.outputs), len(fem.inputs))
