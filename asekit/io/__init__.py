"""Files in and out: Nastran bulk data (through pyNastran), OUTPUT4 matrices, MATLAB and
python-control state spaces."""
