"""The mechanical model: the blank's hexahedral mesh, its material, the solid, the contact
law and the forming problem that solves them together with the rigid tools."""
