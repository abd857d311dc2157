"""The Python side of the doorway to the Fortran core that is not a model of its own: the
sparse linear solver (MUMPS), the fill-reducing ordering of a mesh's unknowns, and the
core's threads. The compiled extension itself is ``ddpy._core`` (fortran/ddpy_core.pyf)."""
