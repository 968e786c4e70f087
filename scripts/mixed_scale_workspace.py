#!/usr/bin/env python3
"""A dense workspace whose views image the hair at two scales, for measuring how the stereo
matches sources across scales (README: `match_source_scale`).

Takes two renders of the same scene at two sizes (`hairmvs synthesize --output_path BASE
--width W` and `--output_path OTHER --width W2`, the same seed and rig) and writes OUT, a copy
of BASE/dense in which the views NAMES come from OTHER: their images, masks and camera (a second
camera in the model), and their sparse observations scaled by W2 / W. The points and poses stay
BASE's (the same scene). Evaluate each size against its own render's gt/:

  python3 scripts/mixed_scale_workspace.py s480 s960 mixed g0_l.png,g0_r.png
  hairmvs orientation_stereo --workspace_path mixed
  hairmvs evaluate_depth --workspace_path mixed --ground_truth_path s480/gt \\
      --image_names g0_c.png,g0_b.png
  hairmvs evaluate_depth --workspace_path mixed --ground_truth_path s960/gt \\
      --image_names g0_l.png,g0_r.png

Needs the `colmap` binary (model_converter) on the PATH. OUT must not exist.
"""
import os
import shutil
import subprocess
import sys
import tempfile


def read_text_model(sparse_dir, txt_dir):
    subprocess.run(["colmap", "model_converter", "--input_path", sparse_dir, "--output_path",
                    txt_dir, "--output_type", "TXT"], check=True, stdout=subprocess.DEVNULL)
    cameras = [l.split() for l in open(os.path.join(txt_dir, "cameras.txt"))
               if l.strip() and not l.startswith("#")]
    images = [l.rstrip("\n") for l in open(os.path.join(txt_dir, "images.txt"))
              if not l.startswith("#")]
    return cameras, images


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    base, other, out, names = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split(",")
    if os.path.exists(out):
        sys.exit("error: %s exists; give a new folder" % out)
    with tempfile.TemporaryDirectory() as tmp:
        base_txt, other_txt = os.path.join(tmp, "base"), os.path.join(tmp, "other")
        os.makedirs(base_txt)
        os.makedirs(other_txt)
        cameras, images = read_text_model(os.path.join(base, "dense", "sparse"), base_txt)
        other_cameras, _ = read_text_model(os.path.join(other, "dense", "sparse"), other_txt)
        if len(cameras) != 1 or len(other_cameras) != 1:
            sys.exit("error: expected one camera in each model (hairmvs synthesize writes one)")
        scale = float(other_cameras[0][2]) / float(cameras[0][2])
        other_id = str(int(cameras[0][0]) + 1)
        shutil.copytree(os.path.join(base, "dense"), out,
                        ignore=shutil.ignore_patterns("depth_maps", "normal_maps", "sparse",
                                                    "orientation_maps", "confidence_maps"))
        os.makedirs(os.path.join(out, "stereo", "depth_maps"), exist_ok=True)
        os.makedirs(os.path.join(out, "stereo", "normal_maps"), exist_ok=True)
        lines, found = [], set()
        for i in range(0, len(images) - 1, 2):
            header, points = images[i].split(), images[i + 1].split()
            if len(header) < 10:
                continue
            name = header[9]
            if name in names:
                found.add(name)
                header[8] = other_id
                for k in range(0, len(points), 3):
                    points[k] = repr(scale * float(points[k]))
                    points[k + 1] = repr(scale * float(points[k + 1]))
                shutil.copy(os.path.join(other, "dense", "images", name),
                            os.path.join(out, "images", name))
                shutil.copy(os.path.join(other, "dense", "masks", name + ".png"),
                            os.path.join(out, "masks", name + ".png"))
            lines += [" ".join(header), " ".join(points)]
        missing = set(names) - found
        if missing:
            shutil.rmtree(out)
            sys.exit("error: no such image in %s: %s" % (base, ", ".join(sorted(missing))))
        mixed_txt = os.path.join(tmp, "mixed")
        os.makedirs(mixed_txt)
        with open(os.path.join(mixed_txt, "cameras.txt"), "w") as f:
            f.write(" ".join(cameras[0]) + "\n" + " ".join([other_id] + other_cameras[0][1:]) +
                    "\n")
        with open(os.path.join(mixed_txt, "images.txt"), "w") as f:
            f.write("\n".join(lines) + "\n")
        shutil.copy(os.path.join(base_txt, "points3D.txt"), mixed_txt)
        os.makedirs(os.path.join(out, "sparse"))
        subprocess.run(["colmap", "model_converter", "--input_path", mixed_txt, "--output_path",
                        os.path.join(out, "sparse"), "--output_type", "BIN"], check=True,
                       stdout=subprocess.DEVNULL)
    print("%s: %s at %.3g times the other views' size" % (out, ", ".join(names), scale))


if __name__ == "__main__":
    main()
