"""The ``fcomp`` command line (public contract in the architecture document)."""
