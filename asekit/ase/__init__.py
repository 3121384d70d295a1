"""The aeroservoelastic loop (thesis Ch. 5): interconnection of the aeroelastic model and the
servo-actuator, stability margins and time-response metrics."""
