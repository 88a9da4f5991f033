#!/usr/bin/env bash
# The Python package as a user installs it (DESIGN.md "Python"): a fresh venv,
# `pip install` of this source tree (the library and the module built by
# scikit-build-core), then `import sysid` and the README's Python example on the
# example logs of a build tree. Slow (a whole library build, about 5 min on 2
# cores): ctest runs it only with the slow label (ctest --preset slow -R python.install).
#
# Usage: scripts/check-python-install.sh DATA_DIR   (a build tree's data/, holding par2_gu.csv)
set -euo pipefail
source_dir="$(cd "$(dirname "$0")/.." && pwd)"
data_dir="$(cd "${1:?usage: $0 DATA_DIR}" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

python3 -m venv "$work/venv"
"$work/venv/bin/pip" install --quiet --disable-pip-version-check "$source_dir" control -Cbuild-dir="$work/build"
cd "$work"
"$work/venv/bin/python" -c "import sysid; print('sysid', sysid.__version__, 'from', sysid.__file__)"
# The README's example, with its paths pointed at DATA_DIR.
"$work/venv/bin/python" - "$source_dir/README.md" "$data_dir" <<'PY'
import sys, warnings
readme, data_dir = sys.argv[1], sys.argv[2]
text = open(readme).read()
start = text.index("```python\nimport control, sysid")
code = text[start + len("```python\n"):text.index("```", start + 10)].replace("build/release/data", data_dir)
with warnings.catch_warnings():
    warnings.simplefilter("ignore", RuntimeWarning)
    exec(compile(code, readme, "exec"), {})
print("the README example ran")
PY
test -s "$work/par2_moesp.json"
echo "check-python-install: passed"
