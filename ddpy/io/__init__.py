"""Input and output: the case (a folder of plain-text decks, validated with file:line
errors), tool files, the HDF5/XDMF results and the checkpoints."""
