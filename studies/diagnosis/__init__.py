"""Model diagnosis on the built-in KR 270: each catalogue effect hidden in turn, found, added.

``python -m studies.diagnosis [--out results]`` or ``doe-calib study diagnosis``.
"""
