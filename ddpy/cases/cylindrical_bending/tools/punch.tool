# cylindrical punch R 23.5 mm, quarter, 4 Nagata patches per arc, normals down
# written by examples/make_tools.py; units mm
ddpy-tool 1
name punch
description nagata
units mm
vertices 10
0 0 1
8.993060661 0 2.788830986
16.61700936 0 7.882990642
21.71116901 0 15.50693934
23.5 0 24.5
0 20 1
8.993060661 20 2.788830986
16.61700936 20 7.882990642
21.71116901 20 15.50693934
23.5 20 24.5
normals 5
0 0 -1
0.3826834324 0 -0.9238795325
0.7071067812 0 -0.7071067812
0.9238795325 0 -0.3826834324
1 0 0
faces 4
# 4 vertices, 4 corner normals, CAD face; counter-clockwise seen from the normals
5 6 1 0 0 1 1 0 1
6 7 2 1 1 2 2 1 1
7 8 3 2 2 3 3 2 1
8 9 4 3 3 4 4 3 1
