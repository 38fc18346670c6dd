"""Physical constants the controller shares (one definition each)."""

GRAVITY_M_S2 = 9.80665  # standard gravity [m/s^2]
