#!/usr/bin/env python3
"""Runs one python/tests file with Debian's python3-pytest (ctest: python_<file>).

Exit status 77, which ctest reports as skipped, with one line saying why, when pytest is missing
(scripts/setup installs python3-pytest); pytest's own status otherwise, where "no test ran" (5)
is a failure like any other.
"""
import sys

try:
    import pytest
except ImportError:
    print("python3-pytest is not installed: skipping the Python tests (scripts/setup installs it)")
    sys.exit(77)

sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", "-rs", *sys.argv[1:]]))
