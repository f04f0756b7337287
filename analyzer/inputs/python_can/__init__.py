"""Log formats read through python-can: ASC, TRC, CSV and MF4, damaged lines reported."""
