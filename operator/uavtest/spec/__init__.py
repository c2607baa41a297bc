"""The model of a UAV test: pydantic models, loaders of native and upstream files, CRD generation."""

from uavtest.spec.models import *  # noqa: F403
from uavtest.spec.models import __all__ as _models_all

__all__ = list(_models_all)
