"""Code run by a fresh Python interpreter: what a command's process imports and sets up."""
import subprocess
import sys


def run_python(code: str, env: dict | None = None) -> str:
    """The standard output of ``code`` run by a new interpreter (this one's executable, its
    environment or ``env``); a failed run fails the test, showing its standard error."""
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out.stdout
