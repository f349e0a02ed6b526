#!/usr/bin/env python3
"""Checks USD files with Pixar's usd-core (installed by .ci/run into
.ci/usd-venv): what `usdchecker` does since USD 0.25, every validator the
UsdValidation registry holds run on the opened stage (usd-core's wheel ships
the library, not the usdchecker program). With --dump, also prints one JSON
line per file: the layer metadata and, per time code, the Mesh prim's points,
normals (with their interpolation; none when the file has no normals) and
extent as pxr.Usd reads them.

Usage: usdcheck.py [--dump] FILE.usda...   (exit 1 on any validation error)
"""
import json
import sys

from pxr import Usd, UsdGeom, UsdValidation


def check(path):
    stage = Usd.Stage.Open(path)
    if stage is None:
        return ["cannot open"], stage
    reg = UsdValidation.ValidationRegistry()
    ctx = UsdValidation.ValidationContext(reg.GetOrLoadAllValidators())
    errors = [
        f"{e.GetName()}: {e.GetMessage()}"
        for e in ctx.Validate(stage)
        if not e.HasNoError()
    ]
    return errors, stage


def dump(stage):
    prim = stage.GetDefaultPrim()
    mesh = UsdGeom.Mesh(prim)
    pts = mesh.GetPointsAttr()
    ext = mesh.GetExtentAttr()
    times = pts.GetTimeSamples()
    nrm = mesh.GetNormalsAttr()
    return {
        "metersPerUnit": UsdGeom.GetStageMetersPerUnit(stage),
        "upAxis": str(UsdGeom.GetStageUpAxis(stage)),
        "timeCodesPerSecond": stage.GetTimeCodesPerSecond(),
        "startTimeCode": stage.GetStartTimeCode(),
        "endTimeCode": stage.GetEndTimeCode(),
        "prim": str(prim.GetPath()),
        "faceVertexCounts": list(mesh.GetFaceVertexCountsAttr().Get()),
        "faceVertexIndices": list(mesh.GetFaceVertexIndicesAttr().Get()),
        "times": list(times),
        "points": [[list(p) for p in pts.Get(t)] for t in times],
        "normalsInterpolation": str(mesh.GetNormalsInterpolation()),
        "normalTimes": list(nrm.GetTimeSamples()),
        "normals": [[list(n) for n in nrm.Get(t)] for t in nrm.GetTimeSamples()],
        "restNormals": [list(n) for n in (nrm.Get() or [])],
        "extent": [[list(p) for p in ext.Get(t)] for t in ext.GetTimeSamples()],
    }


def main():
    args = sys.argv[1:]
    want_dump = "--dump" in args
    files = [a for a in args if a != "--dump"]
    bad = 0
    for f in files:
        errors, stage = check(f)
        for e in errors:
            print(f"{f}: {e}", file=sys.stderr)
        bad += bool(errors)
        if want_dump and stage is not None:
            print(json.dumps(dump(stage)))
    print(f"{len(files) - bad} of {len(files)} passed", file=sys.stderr)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
