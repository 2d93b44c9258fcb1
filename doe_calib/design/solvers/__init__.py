"""The design solvers, each returning a :class:`.outcome.DesignOutcome`: the convex relaxation
with its certified bound (:mod:`.relaxation`), the exact N-pose exchange (:mod:`.exchange`),
the exchange under detection bounds (:mod:`.constrained_exchange`) and the continuous IPOPT
refinement (:mod:`.pose_refinement`, on the expressions of :mod:`.symbolic`)."""
