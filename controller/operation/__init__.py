"""The operation layer's maths ([OP]): operational points, Eq. 5, the dead-man, the per-point limits."""
