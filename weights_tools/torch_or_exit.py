"""Imports torch, or exits 2 saying which interpreter has it (Debian's python3-torch
is installed for /usr/bin/python3 only)."""
import sys


def require_torch():
    try:
        import torch  # noqa: F401
    except ImportError:
        sys.stderr.write(
            f"error: PyTorch is not importable by {sys.executable}; run this script with "
            "/usr/bin/python3 (Debian's python3-torch; scripts/setup-debian --reference)\n")
        sys.exit(2)
    return torch
