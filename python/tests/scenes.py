"""What the array and GDS tests share: the repository's root and the part of their test scene
that is not the lens (a flat source through a 50 nm Gaussian band at 800 nm onto a 5.2 µm camera).

Pytest puts this folder on `sys.path` (its default import mode, no `__init__.py`), so the tests
import it as `scenes`.
"""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: Every table of the test scene after `[lens]`: source, spectrum, camera and exposure.
NOT_THE_LENS = """
[source]
kind = "flat"
radiance_w_m2_sr_nm = 0.025

[spectrum]
shape = "gaussian"
center_nm = 800.0
range_nm = 50.0
peak = 1.0

[camera]
pixel_pitch_um = 5.2
pixel_mtf = false
quantum_efficiency = 0.2

[exposure]
time_ms = 1.23
"""
