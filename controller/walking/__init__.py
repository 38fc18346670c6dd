"""Walking maths: footstep planning, the gait generator (reference ZMP, foot poses), toe-heel, swing,
preview control."""
