"""The lowest layer: the trial data model and the package's error types. Imports no
other part of fuzzygait."""
