"""The paper's studies and benchmark geometries: the arc accuracy study (Fig. 3 and 4), the
analytic geometry of the cylindrical bending and of the reverse deep drawing."""
