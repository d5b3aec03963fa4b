"""SUMO input files as XML element trees (Flow's ``flow.core.util.makexml`` / ``printxml``),
for code that builds its own SUMO files the way Flow's kernel did."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

XSI = "http://www.w3.org/2001/XMLSchema-instance"


def makexml(name: str, nsl: str) -> ET.Element:
    """A root element ``<name>`` whose ``xsi:noNamespaceSchemaLocation`` is ``nsl`` (the SUMO
    schema URL, e.g. ``http://sumo.dlr.de/xsd/routes_file.xsd``)."""
    ET.register_namespace("xsi", XSI)
    return ET.Element(name, {f"{{{XSI}}}noNamespaceSchemaLocation": nsl})


def printxml(t: ET.Element, fn: str | os.PathLike[str]) -> None:
    """Write the element tree ``t`` to ``fn``: UTF-8 with an XML declaration, indented."""
    tree = ET.ElementTree(t)
    ET.indent(tree)
    tree.write(fn, encoding="UTF-8", xml_declaration=True)
