"""The second real validation set shipped with the benchmarks (benchmarks/data/marques2022): every
tile has its masks, the licence and the source travel with it, and the consolidated mask is what
its README says it is, the pixels all three geologists marked."""

from pathlib import Path

import cv2
import numpy as np

DATA = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "marques2022"
GEOLOGISTS = ("O1", "O2", "O3")


def test_licence_source_and_citation_travel_with_the_tiles():
    licence = (DATA / "LICENSE").read_text()
    readme = (DATA / "README.md").read_text()
    assert "MIT License" in licence and "Ademir Marques Junior" in licence
    assert "9de4b03618c229698c0d9a1753c1c557b26e7612" in readme
    assert "10.1109/LGRS.2022.3200311" in readme


def test_every_tile_has_its_masks_and_the_consolidated_one_is_all_three():
    tiles = sorted((DATA / "images").glob("*.png"))
    assert len(tiles) == 20
    for tile in tiles:
        image = cv2.imread(str(tile), cv2.IMREAD_UNCHANGED)
        assert image.shape == (500, 500, 3) and image.dtype == np.uint8
        masks = {name: cv2.imread(str(DATA / "labels" / name / tile.name), cv2.IMREAD_UNCHANGED)
                 for name in ("consolidated", *GEOLOGISTS)}
        for name, mask in masks.items():
            assert mask is not None and mask.shape == (500, 500), (tile.name, name)
            assert set(np.unique(mask)) <= {0, 255}, (tile.name, name)
        every = np.logical_and.reduce([masks[g] > 0 for g in GEOLOGISTS])
        assert np.array_equal(masks["consolidated"] > 0, every), tile.name
        assert every.any(), tile.name
