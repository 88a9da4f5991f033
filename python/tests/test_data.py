"""sysid.read_log and how NumPy arrays cross into the library."""

import threading
import time

import numpy as np
import pytest

import sysid


def test_read_log_gives_the_columns_and_the_sample_time(data_dir):
    u, y, Ts = sysid.read_log(str(data_dir / "par2_gu.csv"), inputs=["u"], outputs=["y"])
    raw = np.genfromtxt(data_dir / "par2_gu.csv", delimiter=",", names=True)
    assert Ts == pytest.approx(0.0005, rel=1e-12)
    np.testing.assert_array_equal(u[:, 0], raw["u"])
    np.testing.assert_array_equal(y[:, 0], raw["y"])


def test_instrument_layouts_are_read(tmp_path):
    log = tmp_path / "semicolon.csv"
    log.write_text("time [ms];force;acc\n0,0;1,5;0,25\n0,5;2,5;0,5\n1,0;3,5;0,75\n1,5;4,5;1,0\n")
    u, y, Ts = sysid.read_log(str(log), ["force"], ["acc"], time_column="time [ms]")
    assert Ts == pytest.approx(0.0005)
    np.testing.assert_array_equal(u[:, 0], [1.5, 2.5, 3.5, 4.5])


def test_a_bad_cell_names_file_line_and_column(tmp_path):
    log = tmp_path / "bad.csv"
    log.write_text("t,u,y\n0,1,2\n0.1,abc,3\n")
    with pytest.raises(sysid.DataError, match=r"bad.csv:3:2: .*abc"):
        sysid.read_log(str(log), ["u"], ["y"])
    good = tmp_path / "good.csv"
    good.write_text("t,u,y\n0,1,2\n0.1,2,3\n")
    with pytest.raises(sysid.DataError, match="no column 'force'; the columns are: t, u, y"):
        sysid.read_log(str(good), ["force"], ["y"])


def test_any_memory_layout_gives_the_same_model(data_dir):
    u, y, Ts = sysid.read_log(str(data_dir / "par2_gu.csv"), ["u"], ["y"])
    reference = sysid.arx(u, y, Ts, na=4, nb=4)
    both_fortran = np.asfortranarray(np.hstack([u, y]))
    both_c = np.ascontiguousarray(np.hstack([u, y]))
    layouts = [(np.ascontiguousarray(u), np.ascontiguousarray(y)), (u[:, 0], y[:, 0]),
               (both_fortran[:, :1], both_fortran[:, 1:]), (both_c[:, :1], both_c[:, 1:])]
    for uu, yy in layouts:
        np.testing.assert_array_equal(sysid.arx(uu, yy, Ts, na=4, nb=4).A, reference.A)
    # integers are converted; a strided view (every other sample) is read through its strides
    assert sysid.fit_percent(np.arange(10), np.arange(10))[0] == 100.0
    np.testing.assert_array_equal(sysid.fit_percent(y[::2], 0.5 * y[::2]),
                                  sysid.fit_percent(np.ascontiguousarray(y[::2]), 0.5 * np.ascontiguousarray(y[::2])))


def test_wrong_shapes_are_value_errors():
    with pytest.raises(ValueError, match="3-D"):
        sysid.fit_percent(np.zeros((3, 2, 2)), np.zeros((3, 2, 2)))
    with pytest.raises(ValueError, match="same record"):
        sysid.n4sid(np.zeros((100, 1)), np.zeros((90, 1)), 0.01, order=2)
    with pytest.raises(ValueError, match="method"):
        sysid.n4sid(np.zeros((100, 1)), np.zeros((100, 1)), 0.01, order=2, method="pem")


def test_long_computations_release_the_gil(data_dir):
    u, y, Ts = sysid.read_log(str(data_dir / "par2_gu.csv"), ["u"], ["y"])
    ticks = []
    done = threading.Event()

    def ticker():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.002)

    thread = threading.Thread(target=ticker)
    thread.start()
    try:
        time.sleep(0.01)
        start = time.perf_counter()
        sysid.armax(u, y, Ts, na=8, nb=8, nc=8, allow_unconverged=True)
        end = time.perf_counter()
    finally:
        done.set()
        thread.join()
    # With the GIL held for the whole fit the ticker could not tick during it.
    during = [t for t in ticks if start < t < end]
    assert end - start > 0.02, "the fit is too short to tell"
    assert len(during) >= 3


def test_file_names_may_be_paths(data_dir, tmp_path):
    u, y, Ts = sysid.read_log(data_dir / "par2_gu.csv", ["u"], ["y"])  # a pathlib.Path, not a str
    model = sysid.arx(u, y, Ts, na=2, nb=2)
    model.write(tmp_path / "arx.json")
    assert sysid.read_model(tmp_path / "arx.json").to_json() == model.to_json()
    model.write_mat(tmp_path / "arx.mat")
    assert (tmp_path / "arx.mat").exists()
