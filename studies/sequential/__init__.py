"""Sequential design on an independently simulated UR10: a first campaign in one IK branch
cannot see the shoulder's own-weight deflection; ``design --augment`` finds the poses that
reveal it."""
