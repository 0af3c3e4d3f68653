"""The bottom layer: the symbolic model (the equations), the curves, the integrators, the plane's rigid motions."""
