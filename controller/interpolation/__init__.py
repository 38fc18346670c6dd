"""Interpolation: Hoff-Arbib minimum-jerk trajectories and the start/stop blend."""
