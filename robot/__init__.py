"""The simulated HRP-2 No.10: model files, their generator and the MuJoCo plant. Imports no other package."""
