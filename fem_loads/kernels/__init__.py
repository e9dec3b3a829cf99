"""The compiled kernels of the DAFL load (numba), in one place: the records a law and the effects are packed into
(:mod:`.records`), the layout of a kernel's data (:mod:`.layout`), the compiled forms of the shared scalar
definitions and the call into a user's law (:mod:`.native`), one surface point's pipeline (:mod:`.point`), the
loop over a mesh's points (:mod:`.mesh_loop`) and the load ring by ring on an exact surface of revolution
(:mod:`.rings`).

Nothing is imported here: the numpy load reads the records without loading numba.
"""
