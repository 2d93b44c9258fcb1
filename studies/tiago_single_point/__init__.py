"""The TIAGo real data reduced to one of its four points: what a single reflector gives,
beside the four-point result, leave one session out."""
