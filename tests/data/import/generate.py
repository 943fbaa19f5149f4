#!/usr/bin/python3
"""Writes the VTK test inputs of tests/import/test_import.cpp with VTK's own
writers (every encoding sluice must read). Run from this directory with
Debian's python3-vtk9:  /usr/bin/python3 generate.py

The reference particles (test_import.cpp has the same formulas; all values
are exact binary fractions, so float32 comparisons are exact):
  i = 0..6, x = i/8, y = -1/2 + i/4, z = 1 + i*i/16
  gid = 100 + 3*(6 - i), rho = 1000 + i/2, velocity = (i, 2i, 2i), |v| = 3i
"""
import math

import vtk

N = 7


def reference(point_type=vtk.VTK_DOUBLE, id_name="gid", id_type=vtk.VTK_INT, poly=False, count=N, first=0):
    points = vtk.vtkPoints()
    points.SetDataType(point_type)
    ids = vtk.vtkDataArray.CreateDataArray(id_type)
    ids.SetName(id_name)
    rho = vtk.vtkDoubleArray()
    rho.SetName("rho")
    vel = vtk.vtkDoubleArray()
    vel.SetName("velocity")
    vel.SetNumberOfComponents(3)
    for i in range(first, first + count):
        points.InsertNextPoint(i / 8, -0.5 + i / 4, 1 + i * i / 16)
        ids.InsertNextTuple1(100 + 3 * (6 - i))
        rho.InsertNextValue(1000 + i / 2)
        vel.InsertNextTuple3(i, 2 * i, 2 * i)
    data = vtk.vtkPolyData() if poly else vtk.vtkUnstructuredGrid()
    data.SetPoints(points)
    if poly:
        verts = vtk.vtkCellArray()
        for k in range(count):
            verts.InsertNextCell(1)
            verts.InsertCellPoint(k)
        data.SetVerts(verts)
    else:
        data.Allocate(count)
        for k in range(count):
            data.InsertNextCell(vtk.VTK_VERTEX, 1, [k])
    for a in (ids, rho, vel):
        data.GetPointData().AddArray(a)
    return data


def write_xml(data, name, mode, zlib=False, encode=True):
    w = vtk.vtkXMLPolyDataWriter() if isinstance(data, vtk.vtkPolyData) else vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(data)
    w.SetFileName(name)
    getattr(w, "SetDataModeTo" + mode)()
    if zlib:
        w.SetCompressorTypeToZLib()
    else:
        w.SetCompressorTypeToNone()
    w.SetEncodeAppendedData(1 if encode else 0)
    assert w.Write() == 1, name


def write_legacy(data, name, binary):
    w = vtk.vtkPolyDataWriter() if isinstance(data, vtk.vtkPolyData) else vtk.vtkUnstructuredGridWriter()
    w.SetInputData(data)
    w.SetFileName(name)
    if binary:
        w.SetFileTypeToBinary()
    else:
        w.SetFileTypeToASCII()
    assert w.Write() == 1, name


def write_parallel_header(name, piece_names, poly):
    """A .pvtu/.pvtp as VTK writes it, pointing at pieces written above."""
    kind = "PPolyData" if poly else "PUnstructuredGrid"
    lines = ['<?xml version="1.0"?>',
             f'<VTKFile type="{kind}" version="0.1" byte_order="LittleEndian" header_type="UInt32">',
             f'  <{kind} GhostLevel="0">',
             '    <PPointData>',
             '      <PDataArray type="Int32" Name="gid"/>',
             '      <PDataArray type="Float64" Name="rho"/>',
             '      <PDataArray type="Float64" Name="velocity" NumberOfComponents="3"/>',
             '    </PPointData>',
             '    <PPoints>',
             '      <PDataArray type="Float64" Name="Points" NumberOfComponents="3"/>',
             '    </PPoints>']
    lines += [f'    <Piece Source="{p}"/>' for p in piece_names]
    lines += [f'  </{kind}>', '</VTKFile>', '']
    with open(name, "w") as f:
        f.write("\n".join(lines))


def main():
    ug = reference()
    write_xml(ug, "ug_ascii.vtu", "Ascii")
    write_xml(ug, "ug_binary.vtu", "Binary")
    write_xml(ug, "ug_binary_zlib.vtu", "Binary", zlib=True)
    write_xml(ug, "ug_appended_raw.vtu", "Appended", encode=False)
    write_xml(ug, "ug_appended_zlib.vtu", "Appended", zlib=True)  # PySPH's encoding
    write_legacy(ug, "ug_ascii.vtk", binary=False)
    write_legacy(ug, "ug_binary.vtk", binary=True)

    # Polydata with float32 points and DualSPHysics' uint32 Idp.
    pd = reference(point_type=vtk.VTK_FLOAT, id_name="Idp", id_type=vtk.VTK_UNSIGNED_INT, poly=True)
    write_xml(pd, "pd_appended_zlib.vtp", "Appended", zlib=True)
    write_legacy(pd, "pd_binary.vtk", binary=True)

    # Two pieces (points 0-3 and 4-6) behind .pvtu and .pvtp headers.
    for poly, ext in ((False, "vtu"), (True, "vtp")):
        names = []
        for k, (first, count) in enumerate(((0, 4), (4, 3))):
            names.append(f"piece_{k}.{ext}")
            write_xml(reference(poly=poly, first=first, count=count), names[-1], "Appended", zlib=True)
        write_parallel_header(f"pieces.p{ext}", names, poly)

    # Non-finite values: positions of particles 2 (NaN) and 4 (Inf); rho of
    # particles 1 (Inf), 2 (NaN, dropped with its particle) and 5 (NaN).
    bad = reference()
    bad.GetPoints().SetPoint(2, math.nan, 0, 0)
    bad.GetPoints().SetPoint(4, 0, math.inf, 0)
    rho = bad.GetPointData().GetArray("rho")
    rho.SetValue(1, math.inf)
    rho.SetValue(2, math.nan)
    rho.SetValue(5, math.nan)
    write_xml(bad, "nonfinite.vtu", "Appended", encode=False)

    # Simulation time in VTK's TimeValue field-data convention.
    timed = reference()
    tv = vtk.vtkDoubleArray()
    tv.SetName("TimeValue")
    tv.InsertNextValue(0.75)
    timed.GetFieldData().AddArray(tv)
    write_xml(timed, "time_value.vtu", "Binary")

    # A file without points, as a writer emits it for an empty dataset.
    write_xml(vtk.vtkPolyData(), "empty.vtp", "Appended", zlib=True)


main()
