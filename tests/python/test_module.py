"""The `lucent` Python module (python/README.md): renders to NumPy arrays equal to `lucent render`'s
files, compares arrays in memory with exactly `lucent compare`'s numbers, releases the GIL while it
renders, and reads every method's dumps as structured arrays with scripts/read-dump.py's dtypes.

Run by ctest with PYTHONPATH=build/python, LUCENT_CLI and LUCENT_SOURCE set:
    /usr/bin/python3 -m pytest -q -p no:cacheprovider tests/python/test_module.py
"""
import importlib.util
import json
import os
import subprocess
import threading

import numpy as np
import pytest

import lucent

CLI = os.environ["LUCENT_CLI"]
SOURCE = os.environ["LUCENT_SOURCE"]
CORNELL = os.path.join(SOURCE, "scenes", "cornell-box.json")


def cli(*args):
    done = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True)
    return done.returncode, done.stdout, done.stderr


@pytest.fixture(scope="module")
def renders(tmp_path_factory):
    """The Cornell box at 32 x 32 by the CLI (a candidate at 16 spp and a reference at 256, both with
    variance) and the candidate again by the module."""
    work = tmp_path_factory.mktemp("module")
    common = ["--resolution", "32x32", "--sampler", "independent", "--variance", "--paths", "--quiet"]
    for name, spp, seed in (("candidate", 16, 1), ("reference", 256, 2)):
        code, _, err = cli("render", CORNELL, "--spp", spp, "--seed", seed, *common, "-o", work / f"{name}.exr")
        assert code == 0, err
    scene = lucent.load_scene(CORNELL, resolution=(32, 32))
    module = lucent.render(scene, method="pt", threads=2, spp=16, seed=1, sampler="independent", variance=True,
                           paths=True)
    return work, module


def test_compare_of_runs_gives_lucent_compares_verdict(renders):
    """Runs (a list of arrays) as `lucent compare RUN... REFERENCE`: the same numbers and verdict, and
    one image without variance layers is inconclusive."""
    work, _ = renders
    runs = []
    for seed in (3, 4, 5):
        path = work / f"run{seed}.exr"
        code, _, err = cli("render", CORNELL, "--resolution", "32x32", "--spp", 16, "--seed", seed, "--quiet", "-o", path)
        assert code == 0, err
        runs.append(path)
    code, out, err = cli("compare", *runs, work / "reference.exr", "--test", "--within", "0.2", "--json")
    assert code in (0, 1, 3), err
    expected = json.loads(out)
    del expected["image"], expected["runs"], expected["reference"]
    reference = lucent.read_image(str(work / "reference.exr"))
    arrays = [lucent.read_image(str(path))["image"] for path in runs]
    assert lucent.compare(arrays, reference, test=True, within=0.2) == expected
    assert expected["verdict"] == {0: "pass", 1: "fail", 3: "inconclusive"}[code]
    assert expected["test"]["candidate_noise"]["source"] == "runs"
    alone = lucent.compare(arrays[0], reference, test=True)
    assert alone["verdict"] == "inconclusive" and "no variance layers" in alone["test"]["candidate_noise"]["undecided"]
    with pytest.raises(ValueError, match="two or more"):
        lucent.compare([arrays[0]], reference, test=True)


def test_the_module_renders_what_lucent_render_writes(renders):
    work, module = renders
    written = lucent.read_image(str(work / "candidate.exr"))
    assert module["image"].shape == (32, 32, 3) and module["image"].dtype == np.float32
    assert np.array_equal(module["image"], written["image"])
    assert np.array_equal(module["variance"], written["variance"])
    assert sorted(module["layers"]) == sorted(written["layers"])
    assert "paths.indirect.1" in module["layers"]
    for name, layer in module["layers"].items():
        assert np.array_equal(layer, written["layers"][name]), name
    assert module["spp"] == 16 and module["complete"]
    assert module["counters"]["invalid_samples"] == 0


@pytest.mark.parametrize("flags", [["--metric", "relmse"], ["--metric", "rmse", "--max-error", "0.01"],
                                   ["--metric", "smape"], ["--metric", "mae"], ["--metric", "flip"],
                                   ["--test"], ["--test", "--block", "4", "--alpha", "0.05"], ["--within", "0.05"],
                                   ["--layer", "indirect.1", "--test"]])
def test_compare_on_arrays_gives_lucent_compares_numbers(renders, flags):
    work, module = renders
    code, out, err = cli("compare", work / "candidate.exr", work / "reference.exr", *flags)
    assert code in (0, 1, 3), err
    expected = json.loads(out)
    del expected["image"], expected["reference"]
    keywords = {}
    for i, flag in enumerate(flags):
        if not flag.startswith("--"):
            continue
        value = flags[i + 1] if i + 1 < len(flags) and not flags[i + 1].startswith("--") else True
        name = flag[2:].replace("-", "_")
        keywords[name] = (float(value) if name in ("max_error", "within", "alpha") else
                          int(value) if name == "block" else value)
    reference = lucent.read_image(str(work / "reference.exr"))
    assert lucent.compare(module, reference, **keywords) == expected
    assert expected["passed"] == (code == 0)
    assert expected["verdict"] == {0: "pass", 1: "fail", 3: "inconclusive"}[code]


def test_compare_refuses_what_lucent_compare_refuses(renders):
    _, module = renders
    with pytest.raises(ValueError, match="shape"):
        lucent.compare(module["image"][:, :, :2], module["image"])
    with pytest.raises(ValueError, match="--within"):
        lucent.compare(module, module, within=20.0)
    with pytest.raises(ValueError):
        lucent.compare(module["image"], module["image"], metric="psnr")
    with pytest.raises(lucent.OptionError, match="sampler"):
        lucent.render(lucent.load_scene(CORNELL, resolution=(8, 8)), spp=4, variance=True)
    with pytest.raises(ValueError, match="no_such_option"):
        lucent.render(lucent.load_scene(CORNELL, resolution=(8, 8)), no_such_option=1)


def test_feature_layers_compare_by_their_own_channels_and_python_keeps_its_denormals(tmp_path):
    code, _, err = cli("render", CORNELL, "--resolution", "16x16", "--spp", "4", "--layers", "--quiet",
                       "-o", tmp_path / "features.exr")
    assert code == 0, err
    scene = lucent.load_scene(CORNELL, resolution=(16, 16))
    module = lucent.render(scene, spp=4, layers=True)
    # Lucent's threads flush denormals; the interpreter's thread that loaded and rendered does not.
    tiny = 5e-324
    assert tiny * 1.0 == tiny and np.float32(1e-45) * np.float32(1.0) != 0
    assert module["layers"]["depth"].shape == (16, 16, 1)
    assert module["layer_channels"]["normal"] == ["X", "Y", "Z"]
    written = lucent.read_image(str(tmp_path / "features.exr"))
    result = lucent.compare(module, written)
    assert result["value"] == 0 and result["passed"]
    assert "depth.Z" in result["channels"] and "normal.X" in result["channels"]


def test_a_render_releases_the_gil():
    scene = lucent.load_scene(CORNELL, resolution=(64, 64))
    result = {}
    thread = threading.Thread(target=lambda: result.update(lucent.render(scene, spp=256, threads=1)))
    ticks = 0
    thread.start()
    while thread.is_alive():
        ticks += 1
    thread.join()
    assert result["spp"] == 256
    # Held through the render, the GIL would leave this loop a handful of turns; released, it runs
    # throughout (the render takes tenths of a second).
    assert ticks > 10000


DUMPING_RENDERS = {
    "purcell": [CORNELL, "--method", "purcell", "--map", "sort", "--photons", "4000"],
    "micro": [CORNELL, "--method", "micro", "--encoding", "packed"],
    "envpbgi": [os.path.join(SOURCE, "scenes", "primitives.json"), "--method", "envpbgi", "--points", "4096"],
    "particles": [CORNELL, "--method", "particles", "--area-particles", "2000"],
}


@pytest.mark.parametrize("method", list(DUMPING_RENDERS))
def test_every_dump_reads_as_read_dump_py_reads_it(tmp_path, method):
    code, _, err = cli("render", *DUMPING_RENDERS[method], "--resolution", "24x24", "--quiet", "--dump", tmp_path,
                       "-o", tmp_path / "image.exr")
    assert code == 0, err
    spec = importlib.util.spec_from_file_location("read_dump", os.path.join(SOURCE, "scripts", "read-dump.py"))
    read_dump = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(read_dump)
    files = sorted(p for p in os.listdir(tmp_path) if p.endswith(".bin"))
    assert len(files) > 5
    for name in files:
        ours = lucent.read_dump(str(tmp_path / name))
        theirs, _ = read_dump.read_dump(str(tmp_path / name))
        assert ours.dtype == theirs.dtype, name
        assert ours.tobytes() == theirs.tobytes(), name


def test_dumps_read_as_structured_arrays(tmp_path):
    code, _, err = cli("render", *DUMPING_RENDERS["purcell"], "--resolution", "24x24", "--quiet", "--dump", tmp_path,
                       "-o", tmp_path / "image.exr")
    assert code == 0, err
    photons = lucent.read_dump(str(tmp_path / "global.photons.bin"))
    assert lucent.record_dtype("Photon").fields["flags"][1] == 28
    assert photons["position"].shape == (len(photons), 3)
    # A damaged dump is refused, naming the file.
    damaged = tmp_path / "damaged.bin"
    damaged.write_bytes((tmp_path / "global.photons.bin").read_bytes()[:100])
    with pytest.raises(RuntimeError, match="damaged.bin"):
        lucent.read_dump(str(damaged))


def test_the_breakdown_by_surface_names_the_references_materials(tmp_path):
    """A reference with layers carries its materials' names: read_image and render give them as
    "materials", and compare breaks the difference down by them, as `lucent compare` does."""
    code, _, err = cli("render", CORNELL, "--resolution", "32x32", "--spp", 64, "--seed", 2, "--sampler",
                       "independent", "--variance", "--layers", "--quiet", "-o", tmp_path / "reference.exr")
    assert code == 0, err
    reference = lucent.read_image(str(tmp_path / "reference.exr"))
    assert "light" in reference["materials"] and "surface" in reference["layers"]
    assert reference["layer_channels"]["surface"] == ["emitter", "material"]
    module = lucent.render(lucent.load_scene(CORNELL, resolution=(32, 32)), spp=4, layers=True)
    assert module["materials"] == reference["materials"]
    assert np.array_equal(module["layers"]["surface"], reference["layers"]["surface"])
    paths = [tmp_path / f"run{seed}.exr" for seed in (3, 4, 5)]
    for seed, path in zip((3, 4, 5), paths):
        code, _, err = cli("render", CORNELL, "--resolution", "32x32", "--spp", 16, "--seed", seed, "--quiet", "-o", path)
        assert code == 0, err
    runs = [lucent.read_image(str(path))["image"] for path in paths]
    code, out, err = cli("compare", *paths, tmp_path / "reference.exr", "--within", "0.2")
    assert code in (0, 1, 3), err
    expected = json.loads(out)
    del expected["image"], expected["runs"], expected["reference"]
    assert lucent.compare(runs, reference, within=0.2) == expected
    names = [entry["name"] for entry in expected["by_surface"]["surfaces"]]
    assert "light" in names and "emitters" in names and "all but emitters" in names


def test_write_dump_writes_what_read_dump_and_check_dump_read(tmp_path):
    """A backend written in Python dumps its arrays with write_dump; check-dump compares them with
    Lucent's, names the shading point's pixel where one differs, and a dump carries its settings."""
    reference, candidate = tmp_path / "reference", tmp_path / "candidate"
    scene = lucent.load_scene(CORNELL, resolution=(16, 16))
    lucent.render(scene, method="purcell", photons=2000, caustic_photons=0, dump=str(reference))
    with open(reference / "settings.json") as f:
        settings = json.load(f)
    assert settings["method"] == "purcell" and settings["width"] == 16 and settings["derived"]["max_radius"] > 0
    points = lucent.read_dump(str(reference / "band0.shading_points.bin"))
    direct = lucent.read_dump(str(reference / "band0.direct.bin"))
    candidate.mkdir()
    lucent.write_dump(str(candidate / "band0.shading_points.bin"), points)  # the type found from the dtype
    changed = direct.copy()
    changed["rgb"][7, 1] += 1
    lucent.write_dump(str(candidate / "band0.direct.bin"), changed, type="Rgb")
    lucent.write_dump(str(candidate / "global.cell_counts.bin"),
                      lucent.read_dump(str(reference / "global.cell_counts.bin")).astype(np.int64), type="uint32")
    assert np.array_equal(lucent.read_dump(str(candidate / "band0.direct.bin")), changed)
    code, out, err = cli("check-dump", reference, candidate)
    assert code == 1, err
    result = json.loads(out)
    compared = {a["name"]: a for a in result["arrays"]}
    assert compared["band0.shading_points"]["passed"] and compared["global.cell_counts"]["passed"]
    first = compared["band0.direct"]["first_differing"][0]
    pixel = int(points["pixel"][7])
    assert first["index"] == 7 and first["field"] == "rgb[1]"
    assert first["where"].startswith("shading point 7: pixel (%d, %d)" % (pixel % 16, pixel // 16))
    assert float(first["candidate"]) == pytest.approx(float(changed["rgb"][7, 1]))
    with pytest.raises(ValueError, match=".bin"):
        lucent.write_dump(str(candidate / "x.dat"), direct)
    with pytest.raises(ValueError, match="dtype"):
        lucent.write_dump(str(candidate / "x.bin"), np.zeros(3, dtype=np.int16))


def test_compare_allows_for_float16_arrays_rounding():
    """Flat 0.7 without noise in either image: a float16 candidate (0.7001953125) passes --test, the
    same values as float32 differ, as lucent compare treats a half-float EXR's colour."""
    zeros = np.zeros((8, 8, 3), dtype=np.float32)
    reference = {"image": np.full((8, 8, 3), 0.7, dtype=np.float32), "variance": zeros}
    halves = np.full((8, 8, 3), 0.7, dtype=np.float16)
    assert lucent.compare({"image": halves, "variance": zeros}, reference, test=True)["test"]["verdict"] == "pass"
    widened = halves.astype(np.float32)
    assert lucent.compare({"image": widened, "variance": zeros}, reference, test=True)["test"]["verdict"] == "fail"


def test_read_image_gives_the_encoding_compare_allows_for():
    """read_image says how a file stored its values, and compare honours it as lucent compare does:
    a JPEG (lossy) is inconclusive even against its own values; without the encoding it passes."""
    jpeg = lucent.read_image(os.path.join(SOURCE, "scenes", "ring", "wood-floorboards-texture.jpg"))
    assert jpeg["encoding"] == "lossy" and jpeg["srgb"]
    zeros = np.zeros_like(jpeg["image"])
    reference = {"image": jpeg["image"].copy(), "variance": zeros}
    candidate = dict(jpeg, variance=zeros)
    assert lucent.compare(candidate, reference, test=True)["test"]["verdict"] == "inconclusive"
    assert lucent.compare({"image": jpeg["image"], "variance": zeros}, reference, test=True)["test"]["verdict"] == "pass"
    with pytest.raises(ValueError, match="unknown encoding 'png'"):
        lucent.compare(dict(candidate, encoding="png"), reference, test=True)
    exr = lucent.read_image(os.path.join(SOURCE, "references", "cornell-box.exr"))
    assert exr["encoding"] == "float" and not exr["srgb"]


def test_integer_codes_are_allowed_their_own_step(tmp_path):
    """An 8-bit PNG reads as integer codes of largest code 255; compare allows a truncated code's
    step below (linear 0.5 as sRGB code 187, 0.49693) for them, not for floats, and an integer
    encoding without its largest code is refused."""
    grey = np.full((8, 8, 3), 0.5, dtype=np.float32)
    code, _, err = cli("render", os.path.join(SOURCE, "scenes", "cornell-box.json"), "--resolution", "8x8",
                       "--spp", "1", "--quiet", "-o", tmp_path / "box.exr", "--png", tmp_path / "box.png")
    assert code == 0, err
    png = lucent.read_image(str(tmp_path / "box.png"))
    assert png["encoding"] == "integer" and png["largest_code"] == 255 and png["srgb"]
    zeros = np.zeros_like(grey)
    reference = {"image": grey, "variance": zeros}
    truncated = np.full_like(grey, (187 / 255 / 1.055 + 0.055 / 1.055) ** 2.4)
    codes = {"image": truncated, "variance": zeros, "encoding": "integer", "largest_code": 255, "srgb": True}
    assert lucent.compare(codes, reference, test=True)["test"]["verdict"] == "pass"
    assert lucent.compare({"image": truncated, "variance": zeros}, reference, test=True)["test"]["verdict"] == "fail"
    with pytest.raises(ValueError, match="largest_code"):
        lucent.compare({k: v for k, v in codes.items() if k != "largest_code"}, reference, test=True)


def test_gltf_choices_load_as_lucent_renders_options_read_them(tmp_path):
    """gltf_masking and gltf_normal_maps give the image the CLI's options of those names give (the
    exported Cornell box read directly: its materials are glTF's), and bad values are refused."""
    box = os.path.join(SOURCE, "scenes", "gltf", "cornell-box.glb")
    code, _, err = cli("render", box, "--resolution", "16x16", "--spp", "4", "--gltf-masking", "separable",
                       "--gltf-normal-maps", "as-given", "--quiet", "-o", tmp_path / "box.exr")
    assert code == 0, err
    scene = lucent.load_scene(box, resolution=(16, 16), gltf_masking="separable", gltf_normal_maps="as-given")
    module = lucent.render(scene, spp=4)
    assert np.array_equal(module["image"], lucent.read_image(str(tmp_path / "box.exr"))["image"])
    # The defaults, height-correlated and bent, as the CLI's.
    code, _, err = cli("render", box, "--resolution", "16x16", "--spp", "4", "--quiet", "-o", tmp_path / "plain.exr")
    assert code == 0, err
    plain = lucent.render(lucent.load_scene(box, resolution=(16, 16)), spp=4)
    assert np.array_equal(plain["image"], lucent.read_image(str(tmp_path / "plain.exr"))["image"])
    assert not np.array_equal(plain["image"], module["image"])
    with pytest.raises(ValueError, match="gltf_masking: expected separable or height-correlated"):
        lucent.load_scene(box, gltf_masking="smooth")
    with pytest.raises(ValueError, match="gltf_normal_maps: expected bend or as-given"):
        lucent.load_scene(box, gltf_normal_maps="flat")
