"""A picture of an HTML report, for ``results/``: headless Chromium, when it is installed."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path


def screenshot(html, png, width: int = 1200, height: int = 5000) -> bool:
    """Render ``html`` to ``png`` (pixels); False, writing nothing, without Chromium."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        return False
    subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu",
                    "--hide-scrollbars", f"--screenshot={Path(png).resolve()}",
                    f"--window-size={width},{height}", Path(html).resolve().as_uri()],
                   check=True, capture_output=True, timeout=120)
    return True
