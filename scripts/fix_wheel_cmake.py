"""Rewrite the wheel builder's include paths in the ROS message wheels' exported CMake files.

About 20 ``share/*/cmake/export_*__rosidl_generator_pyExport.cmake`` files of the ros-jazzy
message wheels hard-code ``/opt/python/cp311-cp311/include/python3.11`` and that interpreter's
numpy include directory; CMake then fails when building our own interfaces (SETUP_NOTES.md,
pitfall 3). This points them at this interpreter's headers. Idempotent.

Usage: python fix_wheel_cmake.py VENV
"""

from __future__ import annotations

import re
import sys
import sysconfig
from pathlib import Path

import numpy

PYTHON_INCLUDE = re.compile(r'/opt/python/[^/;"]+/include/python3\.\d+')
NUMPY_INCLUDE = re.compile(r'/opt/python/[^;"]+/site-packages/numpy/(?:_)?core/include')


def main(venv: Path) -> int:
    """Rewrite every exported CMake file under ``venv/share``; return the process exit code."""
    python_include = sysconfig.get_paths()['include']
    numpy_include = numpy.get_include()
    rewritten = 0
    for path in sorted(venv.glob('share/*/cmake/*.cmake')):
        text = path.read_text()
        if '/opt/python/' not in text:
            continue
        text = NUMPY_INCLUDE.sub(numpy_include, text)
        text = PYTHON_INCLUDE.sub(python_include, text)
        path.write_text(text)
        rewritten += 1
    print(f'[setup] rewrote include paths in {rewritten} CMake files')
    return 0


if __name__ == '__main__':
    sys.exit(main(Path(sys.argv[1])))
