"""FIGAROH's frozen TIAGo protocol: train on one 37-posture session from one point, predict the
other three sessions; ``identify`` with its parameter selection beside ``--select none``."""
