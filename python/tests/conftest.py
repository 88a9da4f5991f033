"""Shared fixtures of the Python tests: the example logs and the program built
beside the package (ctest sets SYSID_TEST_DATA_DIR and SYSID_BINARY; see
python/CMakeLists.txt). A run whose tests were skipped and none failed exits 77,
which ctest reports as skipped, not passed (as the C++ tests do)."""

import os
import pathlib
import subprocess

import pytest


def _path_from_env(name):
    value = os.environ.get(name)
    return pathlib.Path(value) if value else None


@pytest.fixture(scope="session")
def data_dir():
    path = _path_from_env("SYSID_TEST_DATA_DIR")
    if path is None or not (path / "par2_gu.csv").exists():
        pytest.skip("the example logs (SYSID_TEST_DATA_DIR) are not built")
    return path


@pytest.fixture(scope="session")
def sysid_cli():
    path = _path_from_env("SYSID_BINARY")
    if path is None or not path.exists():
        pytest.skip("the sysid program (SYSID_BINARY) is not built")

    def run(*args):
        result = subprocess.run([str(path), *map(str, args)], capture_output=True, text=True)
        assert result.returncode == 0, result.stderr
        return result

    return run


def pytest_sessionfinish(session, exitstatus):
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is None or exitstatus != 0:
        return
    if reporter.stats.get("skipped") and not reporter.stats.get("failed") and not reporter.stats.get("error"):
        session.exitstatus = 77
