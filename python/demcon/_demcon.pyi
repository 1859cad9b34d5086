"""Type stubs of the compiled module demcon._demcon (python/src/*.rs)."""

from os import PathLike
from typing import Any, Callable, Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, PathLike[str]]
_Progress = Union[bool, None, Callable[[str, int, int], Any]]

class SceneError(ValueError):
    """A scene that cannot be read or run; the CLI's message with the field path."""

class Scene:
    """A RON scene, parsed and checked once."""

    @staticmethod
    def from_file(path: _Path) -> Scene: ...
    @staticmethod
    def from_str(
        text: str, base_dir: Optional[_Path] = None, path: Optional[_Path] = None
    ) -> Scene: ...
    @property
    def name(self) -> str: ...
    @property
    def warnings(self) -> list[str]: ...
    def run(
        self,
        out: Optional[_Path] = None,
        threads: Optional[int] = None,
        progress: _Progress = None,
    ) -> RunResult: ...

class RunResult:
    """A run's summary and per-particle fields (SI units; None when not computed)."""

    @property
    def summary(self) -> dict[str, Any]: ...
    @property
    def centres(self) -> npt.NDArray[np.float64]: ...
    @property
    def radii(self) -> npt.NDArray[np.float64]: ...
    @property
    def phase(self) -> npt.NDArray[np.uint16]: ...
    @property
    def volume(self) -> npt.NDArray[np.float64]: ...
    @property
    def temperature(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def heat_flux(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def potential(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def current_density(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def joule_power(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def etc(self) -> Optional[float]: ...
    @property
    def etc_tensor(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def electric_tensor(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def wall_s(self) -> float: ...
