"""Type stubs of the native module (src/lib.rs); use the wrappers in ``ehservo``."""

from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

class ScenarioError(ValueError):
    """A bad scenario, study or override, with the command line's message."""

    file: Optional[str]
    """The file (``<string>`` for TOML text, ``<--set>`` for an override)."""
    key: Optional[str]
    """The key path, e.g. ``controller.gamma1`` (None when the file as a whole is at fault)."""
    line: Optional[int]
    column: Optional[int]
    reason: str

def run(
    path: Optional[str], text: Optional[str], overrides: List[str], raw: bool = False
) -> Tuple[str, Dict[str, Any], List[str], List[npt.NDArray[np.float64]], str]: ...
def check(path: Optional[str], text: Optional[str], overrides: List[str]) -> str: ...
def sweep(
    path: str, threads: Optional[int] = None, out: Optional[str] = None
) -> Tuple[List[str], List[Any]]: ...
def tune(
    path: str, threads: Optional[int] = None, out: Optional[str] = None, plot: bool = True
) -> str: ...
def league(
    path: str, threads: Optional[int] = None, out: Optional[str] = None, plot: bool = True
) -> str: ...
def is_file(p: str) -> bool: ...
def linearize(
    path: Optional[str],
    text: Optional[str],
    overrides: List[str],
    at: Optional[float] = None,
    trim: Optional[float] = None,
    side: Optional[str] = None,
    discretise: str = "zoh",
) -> str: ...
def freq(
    path: Optional[str],
    text: Optional[str],
    overrides: List[str],
    out: str,
    at: Optional[float] = None,
    trim: Optional[float] = None,
    side: Optional[str] = None,
    discretise: str = "zoh",
    measure: List[str] = ...,
    points: Optional[int] = None,
    amplitude: Optional[float] = None,
    threads: Optional[int] = None,
    plot: bool = True,
) -> str: ...

FLAGS: Dict[str, int]

class RawController:
    kind: str
    dt: float
    name: str
    faults: int
    def __init__(self, path: Optional[str], text: Optional[str], overrides: List[str]) -> None: ...
    def step(self, t: float, x: List[float], z: List[float]) -> Dict[str, float]: ...
    def peek(self, t: float, x: List[float], z: List[float]) -> Tuple[float, int]: ...
    def reference(self, t: float) -> Tuple[float, float, float, float]: ...
    def reset(self) -> None: ...
    def signals(self) -> List[Tuple[str, str, str, str]]: ...
    def weights(self) -> npt.NDArray[np.float64]: ...
