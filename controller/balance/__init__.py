"""Balance maths: capture point and support polygons, force distribution QP, hand-force COG offset,
state estimation, fall detection."""
