"""DREAM's own exception; everything else is a standard ``ValueError``/``IndexError``/``KeyError``."""


class GeometryError(ValueError):
    """Input that is well-formed but geometrically impossible (e.g. an obstacle with no area)."""
