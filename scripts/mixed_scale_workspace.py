#!/usr/bin/env python3
"""A dense workspace whose views image the hair at two scales, for measuring how the stereo
matches sources across scales (README: `match_source_scale`).

Takes two renders of the same scene at two sizes (`hairmvs synthesize --output_path BASE
--width W` and `--output_path OTHER --width W2`, the same seed and rig) and writes OUT, a copy
of BASE/dense in which the views NAMES come from OTHER: their images, masks and camera (a second
camera in the model), and their sparse observations taken through OTHER's camera. The points
stay BASE's (the same scene; the views' poses must agree). Evaluate each size against its own
render's gt/:

  python3 scripts/mixed_scale_workspace.py s480 s960 mixed g0_l.png,g0_r.png
  hairmvs orientation_stereo --workspace_path mixed
  hairmvs evaluate_depth --workspace_path mixed --ground_truth_path s480/gt \\
      --image_names g0_c.png,g0_b.png
  hairmvs evaluate_depth --workspace_path mixed --ground_truth_path s960/gt \\
      --image_names g0_l.png,g0_r.png

Needs the `colmap` binary (model_converter) on the PATH. OUT must not exist; it is built in a
temporary folder beside it and renamed into place once complete.
"""
import os
import shutil
import subprocess
import sys
import tempfile


def fail(message):
    sys.exit("error: " + message)


def colmap_convert(input_path, output_path, output_type):
    subprocess.run(["colmap", "model_converter", "--input_path", input_path, "--output_path",
                    output_path, "--output_type", output_type], check=True,
                   stdout=subprocess.DEVNULL)


def read_text_model(sparse_dir, txt_dir):
    """The model's one PINHOLE camera (its fields) and its images (header and points fields)."""
    colmap_convert(sparse_dir, txt_dir, "TXT")
    with open(os.path.join(txt_dir, "cameras.txt")) as f:
        cameras = [l.split() for l in f if l.strip() and not l.startswith("#")]
    if len(cameras) != 1 or cameras[0][1] != "PINHOLE":
        fail("%s: expected one PINHOLE camera (as hairmvs synthesize writes)" % sparse_dir)
    with open(os.path.join(txt_dir, "images.txt")) as f:
        lines = [l.rstrip("\n") for l in f if not l.startswith("#")]
    images = {}
    for i in range(0, len(lines) - 1, 2):
        header = lines[i].split()
        if len(header) != 10:
            fail("%s: malformed image line: %r" % (sparse_dir, lines[i]))
        images[header[9]] = (header, lines[i + 1].split())
    return cameras[0], images


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    base, other, out, names = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split(",")
    if os.path.exists(out):
        fail("%s exists; give a new folder" % out)
    with tempfile.TemporaryDirectory() as tmp:
        base_txt, other_txt, mixed_txt = (os.path.join(tmp, d) for d in ("base", "other", "mixed"))
        for d in (base_txt, other_txt, mixed_txt):
            os.makedirs(d)
        camera, images = read_text_model(os.path.join(base, "dense", "sparse"), base_txt)
        other_camera, other_images = read_text_model(os.path.join(other, "dense", "sparse"),
                                                     other_txt)
        for name in names:
            if name not in images or name not in other_images:
                fail("no image %s in both %s and %s" % (name, base, other))
            pose = [float(v) for v in images[name][0][1:8]]
            other_pose = [float(v) for v in other_images[name][0][1:8]]
            if max(abs(a - b) for a, b in zip(pose, other_pose)) > 1e-9:
                fail("%s has another pose in %s than in %s: not the same scene" %
                     (name, other, base))
        fx, fy, cx, cy = (float(v) for v in camera[4:8])
        ofx, ofy, ocx, ocy = (float(v) for v in other_camera[4:8])
        other_id = str(int(camera[0]) + 1)

        staging = tempfile.mkdtemp(prefix="." + os.path.basename(out) + ".",
                                   dir=os.path.dirname(os.path.abspath(out)))
        try:
            work = os.path.join(staging, "dense")
            shutil.copytree(os.path.join(base, "dense"), work,
                            ignore=shutil.ignore_patterns("depth_maps", "normal_maps", "sparse",
                                                          "orientation_maps",
                                                          "confidence_maps"))
            os.makedirs(os.path.join(work, "stereo", "depth_maps"), exist_ok=True)
            os.makedirs(os.path.join(work, "stereo", "normal_maps"), exist_ok=True)
            lines = []
            for name, (header, points) in images.items():
                if name in names:
                    header = header[:8] + [other_id, name]
                    points = list(points)
                    # Through the other camera: the same ray, COLMAP's image coordinates.
                    for k in range(0, len(points), 3):
                        x, y = float(points[k]), float(points[k + 1])
                        points[k] = repr(ocx + ofx / fx * (x - cx))
                        points[k + 1] = repr(ocy + ofy / fy * (y - cy))
                    shutil.copy(os.path.join(other, "dense", "images", name),
                                os.path.join(work, "images", name))
                    shutil.copy(os.path.join(other, "dense", "masks", name + ".png"),
                                os.path.join(work, "masks", name + ".png"))
                lines += [" ".join(header), " ".join(points)]
            with open(os.path.join(mixed_txt, "cameras.txt"), "w") as f:
                f.write(" ".join(camera) + "\n" + " ".join([other_id] + other_camera[1:]) + "\n")
            with open(os.path.join(mixed_txt, "images.txt"), "w") as f:
                f.write("\n".join(lines) + "\n")
            shutil.copy(os.path.join(base_txt, "points3D.txt"), mixed_txt)
            os.makedirs(os.path.join(work, "sparse"))
            colmap_convert(mixed_txt, os.path.join(work, "sparse"), "BIN")
            os.rename(work, out)
        finally:
            shutil.rmtree(staging, ignore_errors=True)
    print("%s: %s at %.3g times the other views' scale" % (out, ", ".join(names), ofx / fx))


if __name__ == "__main__":
    main()
