"""Bad input raises the right exception with the command line's message, naming the file,
key or value."""

import pytest

import dit_garment as dg


def test_a_missing_recording_is_an_os_error_naming_it(tmp_path):
    path = tmp_path / "missing.mcap"
    with pytest.raises(OSError, match="missing.mcap"):
        dg.read_recording(path)


def test_a_foreign_file_is_an_os_error_naming_it(tmp_path):
    path = tmp_path / "notes.mcap"
    path.write_text("not a recording")
    with pytest.raises(OSError, match=r"notes\.mcap.*not an MCAP file"):
        dg.read_recording(path)


def test_a_truncated_recording_is_named(tmp_path):
    path = tmp_path / "cut.mcap"
    dg.simulate(frames=2).write(path)
    path.write_bytes(path.read_bytes()[:-40])
    with pytest.raises(OSError, match=r"cut\.mcap.*truncated"):
        dg.read_recording(path)


def test_a_missing_motion_file_is_an_os_error_naming_it(tmp_path):
    with pytest.raises(OSError, match="nowhere.npz"):
        dg.simulate(motion=str(tmp_path / "nowhere.npz"), frames=2)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"garment": "no_such_garment"}, "no_such_garment"),
        ({"motion": "moonwalk"}, "moonwalk"),
        ({"material": {"k_s": -1.0}}, "k_s"),
        ({"material": {"stiffness": 1.0}}, "stiffness"),
        ({"material": {"k_s": float("nan")}}, "k_s"),
        ({"betas": [float("inf")]}, "beta"),
        ({"substeps": 0}, "substeps"),
        ({"friction": "high"}, "friction"),
        ({"warp_speed": 9}, "warp_speed"),
        ({"frames": 0}, "frames"),
    ],
)
def test_bad_values_are_value_errors_naming_them(arguments, message):
    kwargs = {"frames": 2, **arguments}
    with pytest.raises(ValueError, match=message):
        dg.simulate(**kwargs)


def test_a_bad_model_folder_is_an_os_error_naming_it(tmp_path):
    with pytest.raises(OSError, match=str(tmp_path.name)):
        dg.predict(model=tmp_path, frames=2)


def test_metrics_refuse_another_template():
    skirt = dg.simulate(frames=2)
    tank = dg.predict(model="builtin-single", garment="tank_tight", frames=3, guidance=0.0)
    with pytest.raises(OSError, match="does not share the garment template"):
        dg.metrics(skirt, tank)


def test_a_bad_split_and_a_missing_dataset_are_named(tmp_path):
    with pytest.raises(ValueError, match="split 'training'"):
        dg.Dataset(tmp_path, split="training")
    with pytest.raises(OSError, match=str(tmp_path.name)):
        dg.Dataset(tmp_path / "none")
    with pytest.raises(OSError, match="manifest.json"):
        dg.TensorShards(tmp_path)


def test_body_refuses_a_wrong_pose_shape():
    with pytest.raises(ValueError):
        dg.body(poses=[0.0] * 10)
