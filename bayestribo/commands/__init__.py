"""Sub-commands of the ``bayestribo`` command line, one module each."""
