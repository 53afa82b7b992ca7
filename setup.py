"""Builds the compiled modules (the plant's kernel, the sampling roll-outs' loop, the speed
profile's passes, the path's frame and projection); everything else is in pyproject.toml."""

from Cython.Build import cythonize
from setuptools import Extension, setup

setup(
    ext_modules=cythonize(
        [
            # Bitwise the Python/numpy code's arithmetic: no fused multiply-adds, no fast-math.
            Extension(
                f"mufusion.{name}",
                [f"src/mufusion/{name.replace('.', '/')}.pyx"],
                extra_compile_args=["-O2", "-ffp-contract=off", "-fno-fast-math"],
            )
            for name in ("vehicle._plant_kernel_c", "planner._rollouts_c",
                         "planner._speed_profile_c", "road._path_c")
        ],
        language_level=3,
    )
)
