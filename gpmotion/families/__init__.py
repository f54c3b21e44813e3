"""Controller families, one module each, on one registered protocol
(:mod:`gpmotion.families.base`)."""
from .base import (Family, family_class, family_names, make_family, recorded_options, register_family,
                   unregister_family)

# the built-in families, in the order `gpmotion list controllers` shows them
from . import gp, bsr_sense, bsr_time  # noqa: E402,F401  (registration)
from . import keyframes  # noqa: E402,F401

DEFAULT_FAMILY = gp.GPFamily.name       # `gpmotion run` without --controller

__all__ = ["DEFAULT_FAMILY", "Family", "family_class", "family_names", "make_family", "recorded_options",
           "register_family",
           "unregister_family"]
