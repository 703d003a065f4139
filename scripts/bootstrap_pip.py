"""Installs pip into the running Python (a virtual environment made with --without-pip).

Downloads the newest pip wheel from PyPI, checks its SHA-256 against the index, and runs pip
from the wheel itself to install it. Used by scripts/test.sh where ensurepip is missing.
"""

import hashlib
import json
import subprocess
import sys
import tempfile
import urllib.parse
import urllib.request
from pathlib import Path


def main() -> None:
    api = "https://pypi.org/pypi/pip/json"
    with urllib.request.urlopen(api, timeout=60) as r:
        index = json.load(r)
    wheel = next(
        u
        for u in index["urls"]
        if u["packagetype"] == "bdist_wheel" and u["filename"].endswith("py3-none-any.whl")
    )
    # The index may give the file's address relative to its own.
    with urllib.request.urlopen(urllib.parse.urljoin(api, wheel["url"]), timeout=300) as r:
        data = r.read()
    digest = hashlib.sha256(data).hexdigest()
    if digest != wheel["digests"]["sha256"]:
        sys.exit(f"bootstrap_pip: {wheel['filename']}: SHA-256 {digest} does not match PyPI's")
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / wheel["filename"]
        path.write_bytes(data)
        # A wheel is a zip that Python can run from: pip installs itself from its own file.
        subprocess.run(
            [sys.executable, str(path / "pip"), "install", "--quiet", "--no-index", str(path)],
            check=True,
        )


if __name__ == "__main__":
    main()
