"""Smooth star gauges (eq. (62)): the radial envelope of a star-shaped polygon and the gauge
g(x) = |x - x_i| / rho~(angle), whose bump b(g) is a size function supported in the star."""
from .envelope import RadialEnvelope
from .star import StarGauge

__all__ = ["RadialEnvelope", "StarGauge"]
