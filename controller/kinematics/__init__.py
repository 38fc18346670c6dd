"""Kinematics and IK: the robot model (pinocchio), closed-form leg IK, whole-body IK, rotations."""
