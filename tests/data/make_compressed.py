"""Remakes the compressed EXR fixtures of tests/envmap_compression.rs with the OpenEXR reference
library (`pip install openexr==3.5.3 numpy`), run from the repository root:

- hall_dwaa.exr, hall_dwab.exr: scenes/env/hall.exr (lossless ZIP) re-compressed as DWAA and
  DWAB, so that hprt's DWA decoding (the exr crate's) is checked against the lossless original
  by an encoder that is not the one under test;
- htj2k.exr, zstd.exr: 16x8 images in compressions the exr crate cannot decode, for the error.
"""
import OpenEXR
import numpy as np

hall = OpenEXR.File("scenes/env/hall.exr", separate_channels=True).channels()
for name, compression in (("dwaa", OpenEXR.DWAA_COMPRESSION), ("dwab", OpenEXR.DWAB_COMPRESSION)):
    header = {"compression": compression, "type": OpenEXR.scanlineimage}
    channels = {c: OpenEXR.Channel(hall[c].pixels) for c in "RGB"}
    OpenEXR.File(header, channels).write(f"tests/data/hall_{name}.exr")

pixels = (np.random.default_rng(1).random((8, 16)) * 4).astype(np.float16)
for name, compression in (("htj2k", OpenEXR.HTJ2K256_COMPRESSION), ("zstd", OpenEXR.ZSTD_COMPRESSION)):
    header = {"compression": compression, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {c: OpenEXR.Channel(pixels) for c in "RGB"}).write(f"tests/data/{name}.exr")
