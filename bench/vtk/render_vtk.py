#!/usr/bin/env python3
"""VTK's vtkFixedPointVolumeRayCastMapper on a volume written by pliant, timed per frame.

    xvfb-run -a /usr/bin/python3 bench/vtk/render_vtk.py VOLUME.nii --tf TF.json --out DIR
        [--size WxH] [--camera AZ,EL,DIST] [--frames N] [--step S] [--opacity-unit U]
        [--threads N]

Reproduces `pliant render VOLUME --tf TF.json --step S --size WxH --camera AZ,EL,DIST`:
the same transfer function (pliant's JSON format, docs/formats.md), the same sampling step and
opacity unit, the same perspective camera (render::frame_box: azimuth from +x towards +y,
elevation towards +z, +z up, 30 degree vertical field of view, the box's bounding sphere grown by
1.1 fitted when DIST is 0), black background, no shading, trilinear interpolation, automatic
sample distance adjustment off, one ray per pixel.

Renders one untimed warm-up frame at AZ, then N timed frames of a turntable around +z (azimuth
AZ + 360 f / N, like `pliant render --orbit N`), each Render() call timed with
time.perf_counter; then renders the view at AZ once more and saves it as DIR/vtk.png. Writes
DIR/vtk_stats.json (atomically). Reads NIfTI (.nii, .nii.gz) only: VTK 9.1's vtkNrrdReader is
replaced by vtkPNrrdReader in Debian's build, which fails without MPI.
"""

import argparse
import json
import math
import os
import sys
import time

import vtk


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("volume", help="NIfTI volume written by pliant (identity rotation)")
    p.add_argument("--tf", required=True, help="transfer function JSON (pliant's format)")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--size", default="512x512", help="image size WxH (default 512x512)")
    p.add_argument("--camera", default="30,20,0",
                   help="AZ,EL,DIST as pliant render --camera (default 30,20,0)")
    p.add_argument("--frames", type=int, default=36, help="timed turntable frames (default 36)")
    p.add_argument("--step", type=float, default=0.0,
                   help="sample distance, world units (default 0: the smallest spacing)")
    p.add_argument("--opacity-unit", type=float, default=0.0,
                   help="opacity unit distance (default: the TF's opacity_unit, else the "
                        "smallest spacing)")
    p.add_argument("--threads", type=int, default=0,
                   help="mapper threads (default 0: VTK's default, every CPU)")
    a = p.parse_args()
    try:
        a.width, a.height = (int(x) for x in a.size.split("x"))
        a.az, a.el, a.dist = (float(x) for x in a.camera.split(","))
    except ValueError:
        p.error("--size WxH and --camera AZ,EL,DIST expected")
    if a.frames < 1:
        p.error("--frames must be >= 1")
    return a


def read_volume(path):
    """The image with VTK's origin set to the first voxel's centre, and pliant's box."""
    reader = vtk.vtkNIFTIImageReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    # vtkNIFTIImageReader leaves the origin at 0 and returns the placement as the qform / sform
    # matrix; pliant writes an identity rotation with the first voxel's centre as translation.
    m = reader.GetQFormMatrix() or reader.GetSFormMatrix()
    origin = [0.0, 0.0, 0.0]
    if m is not None:
        for i in range(3):
            for j in range(3):
                if abs(m.GetElement(i, j) - (1.0 if i == j else 0.0)) > 1e-6:
                    sys.exit("render_vtk: %s: rotated or flipped qform/sform not supported" % path)
            origin[i] = m.GetElement(i, 3)
    copy = vtk.vtkImageData()
    copy.ShallowCopy(image)
    copy.SetOrigin(origin)
    dims, spacing = copy.GetDimensions(), copy.GetSpacing()
    # pliant's box: voxel centres at corner + (i + 0.5) spacing.
    lo = [origin[i] - 0.5 * spacing[i] for i in range(3)]
    hi = [lo[i] + dims[i] * spacing[i] for i in range(3)]
    return copy, lo, hi


def read_tf(path):
    with open(path) as f:
        tf = json.load(f)
    color = vtk.vtkColorTransferFunction()
    color.SetColorSpaceToRGB()  # pliant interpolates r, g, b linearly
    color.ClampingOn()          # outside the points: the first / last point's value, as pliant
    for p in tf["color"]:
        color.AddRGBPoint(float(p["value"]), *[float(c) for c in p["rgb"]])
    opacity = vtk.vtkPiecewiseFunction()
    opacity.ClampingOn()
    for p in tf["opacity"]:
        opacity.AddPoint(float(p["value"]), float(p["alpha"]))
    return tf, color, opacity


def set_camera(camera, lo, hi, az_deg, el_deg, dist, width, height, fov_y=30.0, margin=1.1):
    """pliant's render::frame_box (dist 0) or orbit_camera (dist > 0), perspective."""
    centre = [0.5 * (lo[i] + hi[i]) for i in range(3)]
    radius = 0.5 * math.sqrt(sum((hi[i] - lo[i]) ** 2 for i in range(3)))
    az, el = math.radians(az_deg), math.radians(el_deg)
    d = (math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el))
    if dist <= 0.0:
        half_y = 0.5 * math.radians(fov_y)
        half_x = math.atan(math.tan(half_y) * width / height)
        dist = margin * radius / math.sin(min(half_x, half_y))
    up = (0.0, 0.0, 1.0)
    if abs(math.cos(el)) < 1e-6:
        s = -1.0 if el_deg > 0 else 1.0
        up = (s * math.cos(az), s * math.sin(az), 0.0)
    camera.SetFocalPoint(*centre)
    camera.SetPosition(*[centre[i] + dist * d[i] for i in range(3)])
    camera.SetViewUp(*up)
    camera.SetViewAngle(fov_y)  # vertical (UseHorizontalViewAngle off)
    camera.SetClippingRange(max(1e-6, 0.5 * (dist - radius)), dist + 2.0 * radius)
    return dist


def main():
    a = parse_args()
    os.makedirs(a.out, exist_ok=True)
    t0 = time.perf_counter()
    image, lo, hi = read_volume(a.volume)
    read_s = time.perf_counter() - t0
    spacing = image.GetSpacing()
    smallest = min(spacing)
    tf, color, opacity = read_tf(a.tf)
    step = a.step if a.step > 0 else smallest
    unit = a.opacity_unit if a.opacity_unit > 0 else float(tf.get("opacity_unit", 0.0)) or smallest

    mapper = vtk.vtkFixedPointVolumeRayCastMapper()
    mapper.SetInputData(image)
    mapper.SetBlendModeToComposite()
    mapper.SetAutoAdjustSampleDistances(0)
    mapper.SetLockSampleDistanceToInputSpacing(0)
    mapper.SetSampleDistance(step)
    mapper.SetImageSampleDistance(1.0)
    mapper.SetInteractiveSampleDistance(step)
    if a.threads > 0:
        mapper.SetNumberOfThreads(a.threads)

    prop = vtk.vtkVolumeProperty()
    prop.SetColor(color)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(unit)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()
    prop.IndependentComponentsOn()

    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)

    renderer = vtk.vtkRenderer()
    renderer.AddVolume(volume)
    renderer.SetBackground(0.0, 0.0, 0.0)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.AddRenderer(renderer)
    window.SetSize(a.width, a.height)
    camera = renderer.GetActiveCamera()

    def render(az):
        set_camera(camera, lo, hi, az, a.el, a.dist, a.width, a.height)
        t = time.perf_counter()
        window.Render()
        return (time.perf_counter() - t) * 1e3, mapper.GetTimeToDraw() * 1e3

    warmup_ms, _ = render(a.az)
    ms, mapper_ms = [], []
    for f in range(a.frames):
        wall, draw = render(a.az + 360.0 * f / a.frames)
        ms.append(wall)
        mapper_ms.append(draw)
    render(a.az)
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    png = os.path.join(a.out, "vtk.png")
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(png)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()

    stats = {
        "vtk_version": vtk.vtkVersion.GetVTKVersion(),
        "mapper": "vtkFixedPointVolumeRayCastMapper",
        "opengl": [line.strip() for line in window.ReportCapabilities().splitlines()
                   if line.startswith("OpenGL") and "string" in line][:3],
        "threads": mapper.GetNumberOfThreads(),
        "volume": os.path.abspath(a.volume),
        "dims": list(image.GetDimensions()),
        "spacing": list(spacing),
        "box": [lo, hi],
        "scalar_range": list(image.GetScalarRange()),
        "read_s": read_s,
        "width": a.width,
        "height": a.height,
        "camera": [a.az, a.el, a.dist],
        "settings": {
            "sample_distance": mapper.GetSampleDistance(),
            "image_sample_distance": mapper.GetImageSampleDistance(),
            "auto_adjust_sample_distances": mapper.GetAutoAdjustSampleDistances(),
            "lock_sample_distance_to_input_spacing":
                mapper.GetLockSampleDistanceToInputSpacing(),
            "scalar_opacity_unit_distance": prop.GetScalarOpacityUnitDistance(),
            "interpolation": prop.GetInterpolationTypeAsString(),
            "shade": prop.GetShade(),
            "color_space": "RGB",
            "transfer_function": os.path.abspath(a.tf),
        },
        "frames": a.frames,
        "warmup_ms": warmup_ms,
        "ms_per_frame": ms,
        "mapper_time_to_draw_ms": mapper_ms,
        "mean_ms": sum(ms) / len(ms),
        "min_ms": min(ms),
        "max_ms": max(ms),
        "timing": "wall clock of vtkRenderWindow.Render() per frame (time.perf_counter), frames "
                  "1 ... N of a turntable after one untimed warm-up frame; "
                  "mapper_time_to_draw_ms is the mapper's own GetTimeToDraw()",
        "image": png,
    }
    path = os.path.join(a.out, "vtk_stats.json")
    with open(path + ".tmp-vtk", "w") as f:
        json.dump(stats, f, indent=1)
        f.write("\n")
    os.replace(path + ".tmp-vtk", path)
    print("render_vtk: %d frames of %dx%d, %.1f ms per frame (min %.1f, max %.1f), warm-up %.1f ms"
          % (a.frames, a.width, a.height, stats["mean_ms"], stats["min_ms"], stats["max_ms"],
             warmup_ms))
    return 0


if __name__ == "__main__":
    sys.exit(main())
