"""Log formats read through python-can: ASC, BLF, TRC, CSV and MF4, damaged lines reported."""
