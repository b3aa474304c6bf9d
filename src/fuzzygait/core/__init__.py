"""The lowest layer: the trial data model, the package's error types and the compiled-code
cache (:mod:`.codegen`). Imports no other part of fuzzygait."""
