"""pip install --no-build-isolation .  builds the range_nlm Python module with CMake (the same
target, python/CMakeLists.txt, as the project's build) from Debian's packages, without network.
See docs/python.md."""

import os
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


def project_version():
    with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
        return re.search(r"project\(range_nlm VERSION ([0-9.]+)", f.read()).group(1)


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    """Configures the project with only the Python module on, for this interpreter, builds the
    module's target and puts the built library where setuptools packs it."""

    def build_extension(self, ext):
        build_dir = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        configure = [
            "cmake", "-S", ROOT, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release",
            "-DPython3_EXECUTABLE=" + sys.executable, "-DRANGE_NLM_BUILD_PYTHON=ON",
            "-DRANGE_NLM_BUILD_TESTS=OFF", "-DRANGE_NLM_BUILD_TOOLS=OFF", "-DRANGE_NLM_BUILD_BENCHMARKS=OFF",
            "-DRANGE_NLM_BUILD_ROS=OFF",
        ]
        if shutil.which("ccache"):
            configure += ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache", "-DCMAKE_C_COMPILER_LAUNCHER=ccache"]
        subprocess.check_call(configure)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", "2")
        subprocess.check_call(["cmake", "--build", build_dir, "--target", "range_nlm_python", "-j", jobs])
        built = os.path.join(build_dir, "python", "range_nlm")
        library = [f for f in os.listdir(built) if f.startswith("_range_nlm") and f.endswith(".so")]
        if len(library) != 1:
            raise RuntimeError("range_nlm: expected one _range_nlm*.so in %s, found %s" % (built, library))
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(os.path.join(built, library[0]), target)


setup(
    name="range_nlm",
    version=project_version(),
    description="Non-local denoising of organized range data (depth images, organized point clouds)",
    packages=["range_nlm"],
    package_dir={"": "python"},
    ext_modules=[CMakeExtension("range_nlm._range_nlm")],
    cmdclass={"build_ext": CMakeBuild},
    python_requires=">=3.7",
    install_requires=["numpy"],
    zip_safe=False,
)
