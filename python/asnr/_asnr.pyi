"""Type stubs of the native module (python/src/lib.rs); the user's API is in ``asnr``."""

import os
from typing import Any, final

import numpy as np
import numpy.typing as npt

class SceneError(Exception):
    """A scene that cannot be read, built or evaluated (the command line's message)."""

@final
class Scene:
    """A scene: a scene file's (or a text's) TOML with overrides, and optionally a Python lens."""

    @property
    def label(self) -> str: ...
    @property
    def overrides(self) -> list[str]: ...
    def with_(self, overrides: dict[str, float | int | bool | str | npt.NDArray[np.floating[Any]]]) -> Scene: ...
    def with_phase_map(
        self,
        phase: npt.NDArray[np.floating[Any]],
        *,
        pitch_um: float,
        amplitude: npt.NDArray[np.floating[Any]] | None = None,
        aperture: str | None = None,
        dispersion: str | None = None,
    ) -> Scene: ...
    def with_layout(self, grid: npt.NDArray[np.floating[Any]], *, pitch_um: float) -> Scene: ...
    def with_lens(self, lens: Any) -> Scene: ...
    def to_toml(self) -> str: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...

def load_file(path: str | os.PathLike[str] | None = None) -> Scene: ...
def load_text(text: str, label: str, directory: str | os.PathLike[str]) -> Scene: ...
def load_json(json: str, label: str, directory: str | os.PathLike[str]) -> Scene: ...
def _rebuild_scene(
    text: str,
    label: str,
    directory: str | os.PathLike[str],
    overrides: list[str],
    lens: Any | None,
    arrays: list[tuple[str, str, list[int], npt.NDArray[np.float64]]] | None = None,
) -> Scene: ...
def evaluate(
    scene: Scene, metrics: tuple[str | None, float | None, float | None, str | None] | None = None
) -> tuple[str, str, list[str]]: ...
def evaluate_many(
    scene: Scene,
    keys: list[str],
    columns: list[npt.NDArray[np.float64]],
    threads: int = 0,
    chunk: int = 256,
) -> dict[str, Any]: ...
def axis(lo: float, hi: float, n: int) -> npt.NDArray[np.float64]: ...
def sweep_csv(keys: list[str], rows: list[tuple[list[float], float, float, float, float, bool, str]]) -> str: ...
def mtf(scene: Scene, frequencies: npt.NDArray[np.float64], wavelengths_nm: list[float] = ...) -> str: ...
def compare(
    path: str | os.PathLike[str] | None = None,
    overrides: dict[str, float | int | bool | str] | list[str] | None = None,
    tolerance: float | None = None,
    over: str | None = None,
    threads: int = 0,
) -> tuple[str, list[str]]: ...
def optimize(
    scene: Scene,
    over: list[tuple[str, float, float]],
    objective: str = "asnr",
    xtol: float = 1e-4,
    starts: int = 0,
    max_evaluations: int = 500,
    method: str | None = None,
) -> str: ...
def gradient(
    scene: Scene,
    keys: list[str],
    overrides: dict[str, float | int | bool | str] | list[str] | None = None,
    tolerance: float | None = None,
) -> tuple[str, list[float]]: ...
def check_objective(scene: Scene, keys: list[str], objective: str) -> None: ...
def objective_value(
    scene: Scene, keys: list[str], values: npt.NDArray[np.float64], objective: str = "asnr"
) -> float: ...
def objective_value_and_gradient(
    scene: Scene, keys: list[str], values: npt.NDArray[np.float64], objective: str = "asnr"
) -> tuple[float, npt.NDArray[np.float64]]: ...
def tolerance(
    scene: Scene,
    vary: list[tuple[str, str]],
    samples: int = 1000,
    seed: int = 1,
    objective: str = "asnr",
    budget_s: float = 600.0,
    threads: int = 0,
) -> tuple[str, str]: ...

# a frame: a path (file, folder or pattern) or (name, 2-D float64 array, bits 8 | 16 | 32)
_Frame = str | tuple[str, npt.NDArray[np.float64], int]

def sfr(
    images: list[_Frame],
    roi: str | None = None,
    dark: list[_Frame] = ...,
    gamma: float | None = None,
    transfer: str | os.PathLike[str] | None = None,
    pixel_pitch_um: float | None = None,
    curved: bool = False,
    reach: float | None = None,
) -> str: ...
def measure(
    frames: list[_Frame],
    white: str,
    black: str,
    capped_black: list[_Frame] = ...,
    include_glare: bool = False,
    edge: list[_Frame] = ...,
    edge_roi: str | None = None,
    mtf_csv: str | os.PathLike[str] | None = None,
    pixel_pitch_um: float | None = None,
    compare: Scene | None = None,
) -> str: ...
