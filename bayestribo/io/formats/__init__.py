"""The file formats shipped with the package, one module each (:mod:`bayestribo.io.registry`)."""
