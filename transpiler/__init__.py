"""hh2iec: HEIDENHAIN TNC PLC programs to IEC 61131-3 Structured Text and PLCopen XML, with proof by co-simulation."""

__version__ = "0.1.0"
