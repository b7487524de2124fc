"""Typed signatures of the Rust extension (docstrings: ``help(interslice.X)``)."""

import os
from typing import Any, Literal, Sequence, TypedDict, overload

import numpy as np
import numpy.typing as npt

DEFAULT_METHOD: str
DEFAULT_TOLERANCE: float

class Error(ValueError):
    """Bad input to interslice; the message is one line."""

class Meta(TypedDict, total=False):
    spacing: tuple[float, float, float]
    unit: str
    origin: tuple[float, float, float]
    direction: tuple[tuple[float, float, float], ...]
    structures: list[dict[str, Any]]

class MethodInfo(TypedDict):
    name: str
    description: str
    default: bool

Axis = Literal[0, 1, 2, "x", "y", "z"]
PathLike = str | os.PathLike[str]

def read(path: PathLike) -> tuple[npt.NDArray[Any], Meta]: ...
def write(path: PathLike, array: npt.NDArray[Any], meta: Meta | dict[str, Any] | None = None) -> None: ...
def phantom(
    size: int = 128, seed: int = 1, bits: Literal[8, 16] = 8, noise: float = 0.02
) -> tuple[npt.NDArray[np.uint8] | npt.NDArray[np.uint16], npt.NDArray[np.uint8], Meta]: ...
def evaluate(
    gt: npt.NDArray[Any],
    seg: npt.NDArray[Any],
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    label: int | None = None,
    tolerance: float = 1.0,
    unit: str | None = None,
) -> dict[str, Any]: ...
def overlap(
    gt: npt.NDArray[Any],
    seg: npt.NDArray[Any],
    label: int = 1,
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    unit: str | None = None,
) -> dict[str, Any]: ...
def staple(
    masks: Sequence[npt.NDArray[Any]], label: int | None = None, max_iterations: int = 10000
) -> tuple[npt.NDArray[np.uint8], dict[str, Any]]: ...
@overload
def interpolate(
    labels: npt.NDArray[Any],
    drawn: Sequence[int] | None = None,
    axis: Axis | None = None,
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    image: npt.NDArray[Any] | None = None,
    method: str | None = None,
    max_labels: int = 255,
    confidence: Literal[False] = False,
) -> npt.NDArray[Any]: ...
@overload
def interpolate(
    labels: npt.NDArray[Any],
    drawn: Sequence[int] | None = None,
    axis: Axis | None = None,
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    image: npt.NDArray[Any] | None = None,
    method: str | None = None,
    max_labels: int = 255,
    *,
    confidence: Literal[True],
) -> tuple[npt.NDArray[Any], npt.NDArray[np.float32]]: ...
def methods() -> list[MethodInfo]: ...
def advise(
    labels: npt.NDArray[Any],
    drawn: Sequence[int] | None = None,
    axis: Axis | None = None,
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    image: npt.NDArray[Any] | None = None,
    method: str | None = None,
    count: int = 5,
    max_labels: int = 255,
) -> dict[str, Any]: ...
def threshold(
    image: npt.NDArray[Any],
    method: Literal["otsu", "rosin", "kmeans", "multi-otsu"] = "otsu",
    classes: int | None = None,
    smooth: float = 0.0,
    largest_component: bool = False,
    connectivity: Literal[6, 26] = 6,
    fill_holes: bool = False,
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    unit: str | None = None,
) -> tuple[npt.NDArray[np.uint8] | npt.NDArray[np.uint16], dict[str, Any]]: ...
