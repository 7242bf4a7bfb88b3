"""Robot control: inverse kinematics, arm motion planning and controller execution."""
