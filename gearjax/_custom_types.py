"""Array type aliases used across gearjax (jaxtyping, diffrax `_custom_types.py` style)."""

from __future__ import annotations

from typing import Union

import jax
import numpy as np
from jaxtyping import Array, Bool, Float, Int

ArrayLike = Union[jax.Array, np.ndarray, float, int]
Scalar = Float[Array, ""]
Vector2 = Float[Array, "2"]
Vector3 = Float[Array, "3"]

__all__ = ["Array", "ArrayLike", "Bool", "Float", "Int", "Scalar", "Vector2", "Vector3"]
