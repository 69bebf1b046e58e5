"""The reproduction of Sect. 4 of the paper: ``vpcontact reproduce --out DIR [--quick]``."""
