"""Model variants as types (issue 20): what differs between the members of the model family,
chosen once, by type, where :class:`analogue.Model` is built, and found downstream by dispatch
(a method on the variant object) instead of attribute tests.

- :mod:`.friction`: the friction law, ``model.friction`` -- :class:`Coulomb` (the paper's),
  :class:`Stribeck`, :class:`Cubic` (added to either);
- :mod:`.spring`: the restoring force, ``model.restoring`` -- :class:`Free`, :class:`Spring`;
- :mod:`.noise`: the noise, ``model.noise`` -- :class:`Silent`, :class:`Gaussian`, :class:`Shot`;
- :mod:`.coloured`: :class:`OrnsteinUhlenbeck`, coloured noise (an Ornstein-Uhlenbeck force of
  correlation time ``tau_c``), the first member added as one module plus its line in
  :data:`NOISE_KINDS` (``Model(..., noise=OrnsteinUhlenbeck(tau_c))``).
- :mod:`.words`: what a variant says of itself on a page (``describe``, ``stated_values``,
  ``page_phrases``), composed by :mod:`analogue.report.prose`.

A new noise kind is one module with a :class:`Noise` subclass that names its ``kind``, imported
here (the registration): :data:`NOISE_KINDS` maps the name it has in ``Model.as_dict`` and in an
experiment's TOML (``noise = {kind = "ornstein-uhlenbeck", tau_c = 0.2}``) to the class.
"""
from __future__ import annotations

from typing import Any

from .coloured import OrnsteinUhlenbeck
from .friction import Coulomb, Cubic, FrictionLaw, Stribeck, build_friction
from .noise import Gaussian, Noise, Shot, Silent, build_noise
from .spring import Free, Restoring, Spring, build_restoring

__all__ = ["NOISE_KINDS", "Coulomb", "Cubic", "Free", "FrictionLaw", "Gaussian", "Noise",
           "OrnsteinUhlenbeck", "Restoring", "Shot", "Silent", "Spring", "Stribeck",
           "build_friction", "build_noise", "build_restoring", "noise_from_mapping"]

#: Noise kinds given as ``Model(noise=...)``, by their ``as_dict``/TOML name: a subclass of
#: :class:`Noise` that names a ``kind`` registers itself when its module is imported (above).
NOISE_KINDS: dict[str, type[Noise]] = Noise.registry


def noise_from_mapping(spec: Any) -> Noise:
    """A registered noise kind from its ``as_dict`` form ``{"kind": name, **parameters}``."""
    return Noise.from_mapping(spec)
