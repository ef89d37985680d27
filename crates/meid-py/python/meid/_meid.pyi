"""Type stubs of the extension module meid._meid (see meid/__init__.py for the documentation)."""

from os import PathLike
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class MeidError(Exception): ...
class InputError(MeidError): ...
class MeidWarning(UserWarning): ...
class FileNotFound(MeidError, FileNotFoundError): ...
class FileError(MeidError, OSError): ...

class Run:
    @property
    def summary(self) -> Dict[str, Any]: ...
    @property
    def history(self) -> Optional[Dict[str, npt.NDArray[np.float64]]]: ...
    def to_pandas(self) -> Any: ...
    @staticmethod
    def _from_state(summary_json: str, columns: Optional[bytes]) -> Run: ...

class Model:
    @staticmethod
    def from_file(
        path: Union[str, PathLike[str]], overrides: Optional[Union[str, List[str]]] = None
    ) -> Model: ...
    @staticmethod
    def from_toml(
        text: str, name: str = "<string>", overrides: Optional[Union[str, List[str]]] = None
    ) -> Model: ...
    @staticmethod
    def from_dict(d: Dict[str, Any], name: str = "<dict>") -> Model: ...
    def with_values(self, values: Dict[str, Union[float, int, bool, str]]) -> Model: ...
    def simulate(
        self,
        method: Optional[str] = None,
        duration: Optional[float] = None,
        rate: Optional[float] = None,
        case: str = "as-specified",
        history: bool = True,
    ) -> Run: ...
    def modes(self, count: Optional[int] = None) -> Dict[str, Any]: ...
    @property
    def name(self) -> str: ...
    @property
    def overrides(self) -> List[str]: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def diagnostics(self) -> Dict[str, Any]: ...

_Columns = Tuple[List[str], List[npt.NDArray[np.float64]], List[Optional[str]]]

def sweep_columns(
    model: Model,
    specs: List[str],
    bed_mass_kg: Optional[float] = None,
    threads: Optional[int] = None,
    duration: Optional[float] = None,
) -> _Columns: ...
def montecarlo_columns(
    model: Model,
    specs: List[str],
    samples: int,
    seed: int = 1,
    first: int = 0,
    end: Optional[int] = None,
    threads: Optional[int] = None,
) -> _Columns: ...
def evaluate(
    model: Model,
    names: List[str],
    values: npt.NDArray[np.float64],
    metrics: Optional[List[str]] = None,
    bed_mass_kg: Optional[float] = None,
    threads: Optional[int] = None,
    errors: bool = False,
) -> Union[npt.NDArray[np.float64], Tuple[npt.NDArray[np.float64], List[Optional[str]]]]: ...
def metric_names() -> List[str]: ...
def max_memory() -> int: ...
def set_max_memory(size: Union[int, str]) -> None: ...
def column_unit(name: str) -> Optional[str]: ...

def blows_json(
    model: Model,
    rate_bpm: Optional[float] = None,
    steady: bool = True,
    case: str = "as-specified",
    blows: int = 10,
) -> str: ...
