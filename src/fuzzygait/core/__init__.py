"""The lowest layer: the trial data model, the package's error types, the compiled-code
cache (:mod:`.codegen`) and the checks of a command's paths before any work
(:mod:`.paths`). Imports no other part of fuzzygait."""
