"""Tools for testing fuzzygait itself (not used by the pipelines): the seeded C3D fault
campaign shared by the fuzz tests and ``benchmarks/fuzz_c3d.py``
(:mod:`fuzzygait.testing.c3d_fuzz`)."""
