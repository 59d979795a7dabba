"""PLCopen TC6 XML v2.01: `writer` formats the IEC project the ST back end decided (same POUs,
types and bodies as the ST file); `xsd` fetches, verifies and applies the official schema.
Must not decide anything about the translation: it only formats.
"""
