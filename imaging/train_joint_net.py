"""Train the convolutional joint detector (docs/imaging.md §3.6) and write it as ONNX.

    pip install torch==2.13.0 onnx      # training only; the detector runs on OpenCV
    python -m rockmass.imaging.train_joint_net [--out FILE] [--iterations N] [--seed S]

Training faces (:func:`training_tiles`, seeds from ``--seed``, default :data:`FIRST_SEED`, apart
from the seeds tests and benchmarks use): 120 field-like faces
(:func:`rockmass.imaging.synthetic_field.field_face`, every second one with wide open crevices), 40
tunnel-style ones, 60 plain synthetic faces ("moderate", "hard", "easy" in turn, 400 x 600 px at
8-20 mm per pixel), and 240 random rock textures (:mod:`rockmass.imaging.rock_textures`): every
fourth one as it is, with nothing to find, the others with the joints of 1-3 random sets drawn on
them by :func:`rockmass.imaging.synthetic.joints_on_photo` ("moderate" and "hard" in turn; set
angles, concentrations, lengths and intensities drawn at random, the intensity scaled by 0.1-1, so
that some faces have few joints). No real photograph is used.

Labels: 1 within 1 px of a true centre line, 0 farther than 3 px, not scored in between or on the
field faces' unlabelled minor cracks (:func:`rockmass.imaging.synthetic_field.minor_crack_mask`).
The network (:func:`build_network`) is a U-Net (Ronneberger et al. 2015) of four levels, 8, 16,
24 and 32 channels, 3 x 3 convolutions with batch normalisation and ReLU, the deepest level's
convolutions dilated 1, 2 and 4 times (a field of view of about 150 px), nearest-neighbour
up-sampling. It is fitted to the class-balanced binary cross-entropy (positives weighted by the
ratio of scored negatives to positives in the batch, at most 50) with Adam (Kingma & Ba 2015) and
a one-cycle learning rate (Smith & Topin 2019, peak 3e-3) on batches of 12 tiles of 160 x 160 px
cut at random from the faces, turned by multiples of 90 degrees, mirrored, and their input scaled
by 0.6-1.6 (light of other contrast). About 17 minutes for 3000 iterations on two cores.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

from .joint_net import CNN_MODEL_FILE, net_input
from .learned import MAX_STRETCH, MIN_SPREAD, model_input
from .train_pixel_model import NEGATIVE_PX, POSITIVE_PX  # the same label bands as the pixel model

#: First face seed of the shipped network's training faces. Networks trained from 70 000, 80 000
#: and 90 000 as well were scored in "auto", each at the ratio its rule picks on the real train/
#: photographs (``benchmarks/bench_network_ratio.py --network FILE``): two tied with it, none did
#: better (session 27, docs/imaging.md §3.6). Its record (``joint_cnn.json``) holds this seed.
FIRST_SEED = 60_000

__all__ = ["tile_labels", "training_tiles", "build_network", "train", "main"]

#: Label of a pixel left out of the loss.
UNSCORED = 255
TILE_PX = 160
BATCH = 12
#: Channels of the U-Net's four levels, finest first (``--channels``).
CHANNELS = (8, 16, 24, 32)


def tile_labels(centre_lines, ignore=None) -> np.ndarray:
    """uint8 labels of a face: 1 within :data:`POSITIVE_PX` of a centre line, 0 farther than
    :data:`NEGATIVE_PX`, :data:`UNSCORED` in between and where ``ignore`` holds a negative."""
    import cv2

    distance = cv2.distanceTransform(np.where(centre_lines, 0, 255).astype(np.uint8), cv2.DIST_L2,
                                     cv2.DIST_MASK_PRECISE)
    labels = np.full(distance.shape, UNSCORED, np.uint8)
    labels[distance <= POSITIVE_PX] = 1
    labels[distance > NEGATIVE_PX] = 0
    if ignore is not None:
        labels[(labels == 0) & np.asarray(ignore, bool)] = UNSCORED
    return labels


def _face_input(grey_u8) -> np.ndarray:
    return net_input(model_input(np.asarray(grey_u8, np.float32) / 255.0)).astype(np.float16)


def _random_sets(rng):
    """1-3 joint sets of random angle, concentration, length and intensity (scaled by 0.1-1)."""
    from .synthetic import JointSetSpec

    scale = float(rng.uniform(0.1, 1.0))
    return tuple(JointSetSpec(float(rng.uniform(0, 180)), float(rng.choice([3.0, 10.0, 40.0])),
                              float(rng.uniform(0.8, 3.5)), 0.5, float(rng.uniform(0.3, 0.8)) * scale,
                              float(rng.uniform(0, 0.5)))
                 for _ in range(int(rng.integers(1, 4))))


def training_tiles(first_seed: int = FIRST_SEED, n_field: int = 120, n_tunnel: int = 40,
                   n_plain: int = 60, n_texture: int = 240):
    """(input float16, labels uint8) of every training face in turn (module notes)."""
    from .metrics import render_traces
    from .rock_textures import random_rock
    from .synthetic import joints_on_photo, synthetic_face
    from .synthetic_field import (CREVICE_STYLE, TUNNEL_STYLE, centre_line_mask, field_face,
                                  minor_crack_mask)

    seed = first_seed
    for i in range(n_field + n_tunnel):
        style = TUNNEL_STYLE if i >= n_field else (CREVICE_STYLE if i % 2 else None)
        face = field_face(seed=seed, style=style)
        seed += 1
        yield _face_input(face.image), tile_labels(centre_line_mask(face), minor_crack_mask(face))
    for i in range(n_plain):
        scale = float(np.random.default_rng(seed).uniform(0.008, 0.02))
        face = synthetic_face(("moderate", "hard", "easy")[i % 3], seed=seed, shape_px=(400, 600),
                              m_per_px=scale)
        seed += 1
        yield _face_input(face.image), tile_labels(render_traces(face.truth, face.image.shape, scale) > 0)
    for i in range(n_texture):
        rng = np.random.default_rng(seed + 777)
        rock = random_rock(rng)
        if i % 4 == 3:  # the texture alone: nothing to find
            seed += 1
            yield _face_input(rock), np.zeros(rock.shape, np.uint8)
            continue
        sets = _random_sets(rng)
        face = joints_on_photo(rock, ("moderate", "hard")[i % 2], seed=seed,
                               m_per_px=float(rng.uniform(0.008, 0.02)), sets=sets)
        seed += 1
        yield (_face_input(face.image),
               tile_labels(render_traces(face.truth, face.image.shape, face.m_per_px) > 0))


def build_network(channels=CHANNELS):
    """The U-Net of the module notes (a ``torch.nn.Module``; needs PyTorch)."""
    import torch
    from torch import nn
    from torch.nn import functional

    def block(n_in, n_out, dilation=1):
        return nn.Sequential(nn.Conv2d(n_in, n_out, 3, padding=dilation, dilation=dilation),
                             nn.BatchNorm2d(n_out), nn.ReLU(inplace=True))

    c = channels

    class JointNet(nn.Module):
        def __init__(self):
            super().__init__()
            self.e1 = nn.Sequential(block(1, c[0]), block(c[0], c[0]))
            self.e2 = nn.Sequential(block(c[0], c[1]), block(c[1], c[1]))
            self.e3 = nn.Sequential(block(c[1], c[2]), block(c[2], c[2]))
            self.e4 = nn.Sequential(block(c[2], c[3]), block(c[3], c[3], 2), block(c[3], c[3], 4))
            self.d3, self.d2 = block(c[3] + c[2], c[2]), block(c[2] + c[1], c[1])
            self.d1, self.out = block(c[1] + c[0], c[0]), nn.Conv2d(c[0], 1, 1)

        def forward(self, x):
            def up(t):
                return functional.interpolate(t, scale_factor=2.0, mode="nearest")

            e1 = self.e1(x)
            e2 = self.e2(functional.max_pool2d(e1, 2))
            e3 = self.e3(functional.max_pool2d(e2, 2))
            e4 = self.e4(functional.max_pool2d(e3, 2))
            d3 = self.d3(torch.cat([up(e4), e3], 1))
            d2 = self.d2(torch.cat([up(d3), e2], 1))
            return self.out(self.d1(torch.cat([up(d2), e1], 1)))

    return JointNet()


def _batch(faces, rng):
    """One batch of :data:`BATCH` random tiles (input, labels) as arrays (B, 1, T, T)."""
    inputs, labels = [], []
    for _ in range(BATCH):
        x, y = faces[rng.integers(len(faces))]
        top = rng.integers(0, x.shape[0] - TILE_PX + 1)
        left = rng.integers(0, x.shape[1] - TILE_PX + 1)
        x, y = x[top:top + TILE_PX, left:left + TILE_PX], y[top:top + TILE_PX, left:left + TILE_PX]
        turns = rng.integers(4)
        x, y = np.rot90(x, turns), np.rot90(y, turns)
        if rng.uniform() < 0.5:
            x, y = x[:, ::-1], y[:, ::-1]
        inputs.append(np.ascontiguousarray(x, np.float32) * rng.uniform(0.6, 1.6))
        labels.append(np.ascontiguousarray(y))
    return np.stack(inputs)[:, None], np.stack(labels)[:, None]


def train(faces, *, iterations: int = 3000, seed: int = 0, channels=CHANNELS, report=print):
    """Fit :func:`build_network` (``channels`` per level) to ``faces`` (a list of (input,
    labels)); returns the network in evaluation mode."""
    import torch
    from torch.nn import functional

    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    net = build_network(channels)
    optimiser = torch.optim.Adam(net.parameters(), lr=3e-3)
    schedule = torch.optim.lr_scheduler.OneCycleLR(optimiser, max_lr=3e-3, total_steps=iterations)
    running, t0 = 0.0, time.perf_counter()
    for it in range(iterations):
        inputs, labels = (torch.from_numpy(a) for a in _batch(faces, rng))
        scored = (labels != UNSCORED).float()
        target = (labels == 1).float()
        n_positive = (target * scored).sum().clamp(min=1)
        n_negative = ((1 - target) * scored).sum().clamp(min=1)
        weight = scored * (target * (n_negative / n_positive).clamp(max=50) + (1 - target))
        loss = functional.binary_cross_entropy_with_logits(net(inputs), target, weight=weight,
                                                           reduction="sum") / weight.sum()
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        schedule.step()
        running = 0.98 * running + 0.02 * float(loss.detach())
        if it % 250 == 0 or it == iterations - 1:
            report(f"iteration {it}: loss {running / (1 - 0.98 ** (it + 1)):.4f} "
                   f"({time.perf_counter() - t0:.0f} s)")
    return net.eval()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m rockmass.imaging.train_joint_net",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=str(CNN_MODEL_FILE),
                        help=f"ONNX file (default {CNN_MODEL_FILE}); its record goes beside it (.json)")
    parser.add_argument("--iterations", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=FIRST_SEED,
                        help="first face seed (default %(default)s)")
    parser.add_argument("--channels", default=",".join(map(str, CHANNELS)),
                        help="channels of the four levels, finest first (default %(default)s)")
    parser.add_argument("--faces-for-test", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.iterations < 1:
        parser.error("--iterations must be at least 1")
    try:
        channels = tuple(int(c) for c in args.channels.split(","))
    except ValueError:
        channels = ()
    if len(channels) != 4 or min(channels) < 1:
        parser.error(f"--channels takes four positive integers, e.g. 8,16,24,32; "
                     f"got {args.channels!r}")
    try:
        import torch
    except ImportError:
        parser.error("training needs PyTorch and onnx: pip install torch==2.13.0 onnx")
    torch.set_num_threads(2)
    t0 = time.perf_counter()
    counts = (dict(n_field=1, n_tunnel=0, n_plain=1, n_texture=2) if args.faces_for_test
              else {})  # a few faces, for the test that the command runs through
    faces = list(training_tiles(args.seed, **counts))
    t_faces = time.perf_counter() - t0
    net = train(faces, iterations=args.iterations, seed=0, channels=channels,
                report=lambda line: print(line, file=sys.stderr, flush=True))
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    torch.onnx.export(net, torch.zeros(1, 1, 64, 64), str(out), dynamo=False, input_names=["x"],
                      output_names=["logit"], opset_version=13,
                      dynamic_axes={"x": {2: "h", 3: "w"}, "logit": {2: "h", 3: "w"}})
    info = {"command": "python -m rockmass.imaging.train_joint_net " + " ".join(argv or sys.argv[1:]),
            "seed": args.seed, "iterations": args.iterations, "faces": len(faces),
            "channels": list(channels), "parameters": int(sum(p.numel() for p in net.parameters())),
            "faces_s": round(t_faces, 1), "total_s": round(time.perf_counter() - t0, 1),
            "python": platform.python_version(), "torch": torch.__version__,
            "data": "synthetic faces and joints drawn on random textures (procedural, and "
                    "scikit-image's CC0 gravel and brick photographs); no real photograph",
            "input": {"min_face_spread": MIN_SPREAD, "max_stretch": MAX_STRETCH}}
    out.with_suffix(".json").write_text(json.dumps(info, indent=2) + "\n")
    print(json.dumps(info, indent=2))
    print(f"wrote {out} ({out.stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
