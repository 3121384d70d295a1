"""The servo-actuator: DC motor and transmission, controllers, torque requirement and the
power-limited simulation (thesis Ch. 4)."""
