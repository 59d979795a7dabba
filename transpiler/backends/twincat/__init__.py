"""The TwinCAT 3 PLC project folder: the project as TwinCAT stores it, one file per object.

In: the `TargetProject` laid out for TwinCAT (st/dialect.py). `layout` decides the folder, the file of every POU,
global variable list, data type and the task, and their deterministic GUIDs, and takes each object's declaration
and body from the ST printer (the same text project.st holds); `writer` formats them with the templates of
templates/twincat as `.plcproj`, `.TcPOU`, `.TcGVL`, `.TcDUT` and `.TcTTO` files. Out: file contents, never written
here. Must not decide anything about the translation: it only arranges and formats what the ST back end decided.
"""
