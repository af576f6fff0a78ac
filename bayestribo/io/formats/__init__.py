"""The file formats shipped with the package, one module each, each defining ``FORMAT``
with its reader; what each format is (name, suffixes, options) is listed in
:data:`bayestribo.io.registry.BUILTIN_FORMATS`."""
