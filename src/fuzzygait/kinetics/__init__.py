"""Kinetics: force plates in the laboratory frame (:mod:`fuzzygait.kinetics.plates`) and
the inverse dynamics built on them."""
