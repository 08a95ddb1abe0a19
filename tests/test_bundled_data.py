"""The data bundled in handsim.assets is byte for byte the real sample data of ``../shared/data``.

The SHA-256 of every bundled data file was taken from ``../shared/data`` (where the project's data lives;
a user's clone does not have it) when the copy was made, so these tests run everywhere and fail if a
bundled file changes. The files that are handsim's own (``LICENSE``, ``README.md``, ``NOTICE``) are not
pinned.
"""

from __future__ import annotations

import hashlib

import pytest

from handsim.assets import ASSETS_DIR

SHARED_SHA256 = {
    "tzionas_ijcv16/Calibration/Cameras.txt": (
        "aec17a4c1ac4133ecb4d4c16baa3895b40a4001da38e616f7dc274cb4d524ee0"
    ),
    "tzionas_ijcv16/Configs/17/INDEX_BOUNDS.txt": (
        "489bd1d7374c8141bf45a051b7474c2bae68109b6d6e5f7b4da9c2264ac9d246"
    ),
    "tzionas_ijcv16/Configs/17/MODELS_INFO.txt": (
        "8d1e0da8044f101e827e602abfc12b368a578c1f9443738a74388e5b2a6f759d"
    ),
    "tzionas_ijcv16/Configs/20/INDEX_BOUNDS.txt": (
        "e9fe5ca6d0ca1b8b374dd5916fca0c64fe6b0d00181ebbcd08cf84b33e2ddfbb"
    ),
    "tzionas_ijcv16/Configs/20/MODELS_INFO.txt": (
        "107a794aeaca70b4963029b93df2c8ba33f232548ce91c6e114e0c767b891a35"
    ),
    "tzionas_ijcv16/Models/17/Model_Object_Pipe_Gray.LIMITS": (
        "fe3942abb45963de605f459bc8b7f03cd1a78b6cf2836fd3454e90fa86b24063"
    ),
    "tzionas_ijcv16/Models/17/Model_Object_Pipe_Gray.MOTION": (
        "6808242174cbc9f27698093dda967245eb794965a0de85d9802f31b0f8af2399"
    ),
    "tzionas_ijcv16/Models/17/Model_Object_Pipe_Gray.OFF": (
        "f1503b5f73ee7a4e48ce2b4ad359b2b40b9a0017c830d1df10946a861fbd0917"
    ),
    "tzionas_ijcv16/Models/17/Model_Object_Pipe_Gray.SKEL": (
        "23946c9d90b235537dc180edb0f34eacd0ab424b0fc880f4124943be42c2c4f4"
    ),
    "tzionas_ijcv16/Models/17/Model_Object_Pipe_Gray.SKIN": (
        "8a056f8d1d60e1313a398ca7ce1c1f8b075798d7a09a2f2377ddad0b13d48310"
    ),
    "tzionas_ijcv16/Models/17/Model_Object_Pipe_Gray.ZONES": (
        "511ec0f7e43cac6b1d790721ff19dfb6e3c28f32507ecb2f8e6342d88dda3c2d"
    ),
    "tzionas_ijcv16/Models/20/Model_Hand_R.LIMITS": (
        "2988919f7470ae43af0422a7496b9562c3f9e9c0cbeaf195b25b541f87824dcd"
    ),
    "tzionas_ijcv16/Models/20/Model_Hand_R.MOTION": (
        "1833e0a4559ef15766f7b7903fdafa51afc62b0c2ad101451698f968b8fb5a9a"
    ),
    "tzionas_ijcv16/Models/20/Model_Hand_R.OFF": (
        "9c5b81d6d54a8d016074d05adddd394b75a316dd36a1a9e492cd8bc237b83a62"
    ),
    "tzionas_ijcv16/Models/20/Model_Hand_R.SKEL": (
        "e2d53866b2c1d4f0f43903f92f61d418fa33f9b9ad1365f7ac490b7abbcfeb58"
    ),
    "tzionas_ijcv16/Models/20/Model_Hand_R.SKIN": (
        "b0d35401b8483de62119bfff7ff5df75736a14a1371448a700762696060a0674"
    ),
    "tzionas_ijcv16/Models/20/Model_Hand_R.VOI": (
        "990d1c017898dfe2581a8a72c2b656953145a42ef90db0468c0bffad968bfbb5"
    ),
    "tzionas_ijcv16/Models/20/Model_Hand_R.ZONES": (
        "4d81683fb956d18efc2579f26321249f03ffae237f1276685500b4bde59c978b"
    ),
    "tzionas_ijcv16/Models/20/Model_Object_Cube.LIMITS": (
        "fe88b15fb29cc005c0f806c9a6ed5c1404cbde6464f77fef7f342805e0b3643e"
    ),
    "tzionas_ijcv16/Models/20/Model_Object_Cube.MOTION": (
        "7a12a621caeabb01e29eb047b778582da246d8c27ecf4791b215a0fb3778a162"
    ),
    "tzionas_ijcv16/Models/20/Model_Object_Cube.OFF": (
        "99a939a37348016e4f096bf323bbe23543e6550cf099a409ed69cc3105fdb191"
    ),
    "tzionas_ijcv16/Models/20/Model_Object_Cube.SKEL": (
        "25d2b9f7c7fb779342c819f2b49e4e3b9573418987f1ed91756631cab19ab990"
    ),
    "tzionas_ijcv16/Models/20/Model_Object_Cube.SKIN": (
        "0f50056df1528658227dbf7e22cd934044f52336b93b516c0c2323d1353eab15"
    ),
    "tzionas_ijcv16/Models/20/Model_Object_Cube.ZONES": (
        "9ff892e9dda39536335fd6279fd6062edbfe1d629f8c94b7f8045d5bdee93a60"
    ),
    "tzionas_ijcv16/VOIs/VOIs_Model_0.txt": (
        "b784feb82c9a140b1b8a634677998fe6d6bfcc22ec545ff8ab01dbf0a6349d6d"
    ),
    "tzionas_ijcv16/VOIs/VOIs_Model_1.txt": (
        "4a1aedff497928e46df6bd564e496a6e48f385ba729c5556dffbe43fba30f09d"
    ),
    "mano/mano_right_mean_joints.json": "e734e72205365c719b7eccf2698af75a9633a99f5c256266905083a12b74bd97",
}
"""Bundled path (under ``handsim/assets``) → SHA-256 of the same file in ``../shared/data``."""


@pytest.mark.parametrize("name", sorted(SHARED_SHA256))
def test_bundled_file_is_the_shared_data_file(name: str) -> None:
    assert hashlib.sha256((ASSETS_DIR / name).read_bytes()).hexdigest() == SHARED_SHA256[name]


def test_every_bundled_data_file_is_pinned() -> None:
    own = {"LICENSE", "README.md", "NOTICE"}
    bundled = {
        str(p.relative_to(ASSETS_DIR))
        for folder in ("tzionas_ijcv16", "mano")
        for p in (ASSETS_DIR / folder).rglob("*")
        if p.is_file() and p.name not in own
    }
    assert bundled == set(SHARED_SHA256)


def test_bundled_notices_are_kept() -> None:
    assert "Copyright (c) 2014 cvlabbonn" in (ASSETS_DIR / "tzionas_ijcv16" / "LICENSE").read_text()
    assert (ASSETS_DIR / "mano" / "NOTICE").read_text().count("MANO") >= 3
