"""Kinematics and IK: the robot model (pinocchio), the one limb IK (damped least squares), closed-form leg IK,
whole-body IK, rotations."""
