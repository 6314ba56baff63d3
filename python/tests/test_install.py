"""`cmake --install` puts the module in the interpreter's package directory
under the prefix, from where it imports."""
import os
import pathlib
import subprocess
import sys

from conftest import BINARY_DIR


def test_install_into_a_temporary_prefix_imports(tmp_path):
    cmake = os.environ.get("LODESTONE_CMAKE", "cmake")
    subprocess.run([cmake, "--install", str(BINARY_DIR), "--prefix", str(tmp_path), "--component", "python"],
                   check=True, capture_output=True)
    modules = list(tmp_path.rglob("lodestone*.so"))
    assert len(modules) == 1
    package_dir = modules[0].parent
    assert package_dir.name in ("site-packages", "dist-packages")
    assert package_dir.parent.name == f"python{sys.version_info.major}.{sys.version_info.minor}"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = str(package_dir)
    out = subprocess.run([sys.executable, "-c", "import lodestone; print(lodestone.__file__); "
                          "print(lodestone.paper_material().saturation)"], env=env, check=True,
                         capture_output=True, text=True).stdout.split()
    assert pathlib.Path(out[0]).resolve() == modules[0].resolve()
    assert abs(float(out[1]) - 8.27e4) < 0.01e4
