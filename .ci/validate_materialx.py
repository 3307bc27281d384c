"""Validate MaterialX documents with the MaterialX library (PyPI: MaterialX):

    python .ci/validate_materialx.py FILE.mtlx...

Each document is read with the standard data libraries imported, so that
`validate()` checks every node and input against its definition; it must
also hold exactly one material whose shader is a `standard_surface`. Exits 1
when any document fails.
"""

import sys

import MaterialX as mx


def check(path, libraries):
    doc = mx.createDocument()
    doc.importLibrary(libraries)
    mx.readFromXmlFile(doc, path)
    ok, message = doc.validate()
    materials = doc.getMaterialNodes()
    shaders = [mx.getShaderNodes(m) for m in materials]
    if ok and (len(materials) != 1 or [s.getCategory() for s in shaders[0]] != ["standard_surface"]):
        ok, message = False, "expected one material with a standard_surface shader"
    if ok:
        # Every input is one the node's definition declares.
        for node in shaders[0]:
            nodedef = node.getNodeDef()
            missing = [i.getName() for i in node.getInputs() if nodedef is None or nodedef.getActiveInput(i.getName()) is None]
            if missing:
                ok, message = False, f"{node.getName()}: inputs without a definition: {missing}"
    print(f"{path}: {'valid' if ok else 'INVALID'} (MaterialX {mx.getVersionString()}){'' if ok else ': ' + message.strip()}")
    return ok


def main(paths):
    if not paths:
        print("usage: validate_materialx.py FILE.mtlx...", file=sys.stderr)
        return 1
    libraries = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), libraries)
    results = [check(p, libraries) for p in paths]
    return 0 if all(results) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
