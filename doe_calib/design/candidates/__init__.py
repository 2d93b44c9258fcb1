"""The candidate poses of a design: what a pose must satisfy (:mod:`.constraints`, read by
:mod:`.constraint_file`, evaluated by :mod:`.feasibility`), poses drawn at random
(:mod:`.draw`) or read from a file (:mod:`.from_file`), whether a program reaches them from
home (:mod:`.reachability`) and their clearances (:mod:`.clearances`)."""
