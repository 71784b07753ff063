"""The simulated scene: the `sim:` URI, scene files, one scene per key, the people
(operator's script, bystanders' behaviours) and the capture noise."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from proxima.ingest import SourceError
from proxima.sim import registry
from proxima.sim.config import (
    DEFAULT_BYSTANDERS,
    BystanderConfig,
    OperatorConfig,
    SceneConfig,
    SceneFileError,
    build_scene,
    load_scene_config,
)
from proxima.sim.noise import CaptureNoise
from proxima.sim.people import ScriptError, parse_script
from proxima.sim.source import fixed_camera
from proxima.sim.uri import parse_sim_uri
from proxima.synth.camera import Camera
from proxima.synth.joints import limit_violations
from proxima.types import Sight

REPO = Path(__file__).resolve().parents[2]


def test_uri_keys_split_into_scene_and_camera() -> None:
    u = parse_sim_uri("sim:operator?script=hover:2,land:3&seed=4&at=-5,1,2&hfov=60&size=640x360")
    assert u.scene == "operator" and u.drone is None
    assert dict(u.scene_options) == {"script": "hover:2,land:3", "seed": "4"}
    assert u.at == (-5.0, 1.0, 2.0) and u.hfov_deg == 60.0 and u.size == (640, 360)
    d = parse_sim_uri("sim:config/scenes/demo.toml?jitter=0&zjitter=0.5#main")
    assert d.drone == "main" and d.jitter == 0.0 and d.depth_jitter == 0.5
    # Equal scenes get equal keys: the script is normalised.
    a = parse_sim_uri("sim:operator?script=hover:2.0, land:3")
    assert a.scene_options == parse_sim_uri("sim:operator?script=hover:2,land:3").scene_options


@pytest.mark.parametrize(
    ("uri", "message"),
    [
        ("sim:", "no scene"),
        ("sim:operator?colour=red", "unknown key 'colour'"),
        ("sim:operator?script=jump:3", "script step 'jump': not a gesture"),
        ("sim:operator?script=hover:-1", "must lie in"),
        ("sim:operator?at=1,2", "expected NORTH,EAST,HEIGHT"),
        ("sim:operator?hfov=200", "hfov=200"),
        ("sim:operator?size=big", "size='big'"),
        ("sim:operator?bystanders=9", "bystanders='9'"),
        ("sim:operator?seed=1&seed=2", "seed given twice"),
        ("sim:operator?at=1,2,3#main", "the drone's camera goes where the drone goes"),
        ("sim:operator?look=0,0,1&yaw=3", "not both"),
        ("sim:operator?jitter=9", "jitter=9"),
    ],
)
def test_bad_uris_are_refused_naming_the_key(uri: str, message: str) -> None:
    with pytest.raises(SourceError, match=message):
        parse_sim_uri(uri)


def test_one_scene_per_scene_key() -> None:
    a = registry.scene_for(parse_sim_uri("sim:operator?script=hover:2&at=-4,0,2"))
    b = registry.scene_for(parse_sim_uri("sim:operator?script=hover:2&hfov=60#x"))
    c = registry.scene_for(parse_sim_uri("sim:operator?script=hover:3"))
    assert a is b and a is not c
    assert len(registry.scenes()) == 2
    registry.register_scene("mine", c)
    assert registry.scene_for(parse_sim_uri("sim:mine")) is c
    with pytest.raises(SourceError, match="registered by this process"):
        registry.scene_for(parse_sim_uri("sim:mine?seed=3"))
    with pytest.raises(SourceError, match="no scene 'elsewhere'"):
        registry.scene_for(parse_sim_uri("sim:elsewhere"))


def test_the_shipped_scene_file_and_bad_ones(tmp_path: Path) -> None:
    cfg = load_scene_config(REPO / "config" / "scenes" / "demo.toml")
    assert cfg.loop and len(cfg.bystanders) == 2 and cfg.capture.depth_jitter == 0.0
    assert [g for g, _ in parse_script(cfg.operator.script)][:2] == ["hover", "have_command"]
    bad = tmp_path / "bad.toml"
    bad.write_text(
        'fps = 30\n[operator]\nscript = "hover:3,fly:2"\n[[bystanders]]\nbehaviour = "dance"\n'
    )
    with pytest.raises(SceneFileError) as err:
        load_scene_config(bad)
    text = str(err.value)
    assert str(bad) in text and "operator.script" in text and "bystanders.0.behaviour" in text
    with pytest.raises(SceneFileError, match="no such scene file"):
        load_scene_config(tmp_path / "none.toml")
    (tmp_path / "broken.toml").write_text("fps = [")
    with pytest.raises(SourceError, match="not valid TOML"):
        registry.scene_for(parse_sim_uri(f"sim:{tmp_path / 'broken.toml'}"))


def test_scripts() -> None:
    assert parse_script("hover:4, idle:1 ,land:2.5") == [
        ("hover", 4.0),
        ("idle", 1.0),
        ("land", 2.5),
    ]
    assert parse_script([["wave_off", 3]]) == [("wave_off", 3.0)]
    for text, msg in (("", "no steps"), ("hover", "GESTURE:SECONDS"), ("hover:x", "not a number")):
        with pytest.raises(ScriptError, match=msg):
            parse_script(text)


def test_the_operator_performs_the_script_and_everyone_moves_within_the_joint_limits() -> None:
    cfg = SceneConfig(
        seed=1,
        operator=OperatorConfig(script="hover:3,have_command:3"),
        bystanders=list(DEFAULT_BYSTANDERS),
    )
    scene = build_scene(cfg, "people")
    assert [p.behaviour for p in scene.people] == ["operator", "arms", "walk", "stand", "gestures"]
    assert {p.world.shape for p in scene.people} == {(scene.frames, 33, 3)}
    truth = scene.truth()
    assert [s["gesture"] for s in truth] == ["hover", "have_command"]
    # Each step lasts its seconds, plus a hesitation of up to 1 s now and then (synth).
    assert 3.0 <= truth[0]["end_t"] - truth[0]["onset_t"] <= 4.05
    for person in scene.people:
        assert limit_violations(person.world) == [], person.name  # NED is right-handed
    # The walker walks: its feet alternate and it covers its path, on the ground.
    walker = scene.people[2]
    hips = walker.world[:, [23, 24]].mean(axis=1)
    assert np.ptp(hips[:, 1]) > 5.0  # east -5 .. 5, less the turns' pauses
    ahead = walker.world[:, 27] - walker.world[:, 28]
    along = np.einsum("ti,ti->t", ahead[:, :2], np.gradient(hips[:, :2], axis=0))
    assert (along > 0.005).any() and (along < -0.005).any()
    assert walker.world[..., 2].max() < 0.05  # nobody sinks into the ground
    # The arm-waving bystander's arms go up; the standing one's stay down.
    wrist_up = scene.people[1].world[:, 15:17, 2].min()
    assert wrist_up < scene.people[1].world[:, 11:13, 2].min()
    assert scene.people[3].world[:, 15:17, 2].min() > scene.people[3].world[:, 11:13, 2].max()


def test_the_default_camera_frames_the_operator_and_bystanders_are_seen() -> None:
    scene = registry.scene_for(parse_sim_uri("sim:operator?bystanders=2"))
    cam = fixed_camera(parse_sim_uri("sim:operator?bystanders=2"), scene)
    assert cam.position[2] == pytest.approx(-1.8)
    view = scene.view(cam, 30)
    assert view.operator_sight == Sight.FULL
    seen = {p.person for p in view.people if p.pose is not None}
    assert {"operator", "bystander1"} <= seen  # the walker may be off-frame at this instant
    assert all(p.pose is None or p.pose.image_size == (1280, 720) for p in view.people)
    behind = Camera.looking_at((5.0, 0.0, -1.8), (10.0, 0.0, -1.0))  # looking away
    assert scene.view(behind, 30).poses == ()


def test_capture_noise_grows_as_the_person_shrinks() -> None:
    scene = build_scene(SceneConfig(operator=OperatorConfig(script="hover:2")), "noise")
    op = scene.operator
    rng = np.random.default_rng(0)
    spread = []
    for distance in (4.0, 12.0):
        cam = Camera.looking_at((-distance, 0.0, -1.6), op.chest(0), width=1280, height=720)
        clean = scene.view(cam, 20).people[0].pose
        assert clean is not None
        torso = np.linalg.norm(clean.xyz[[11, 12], :2].mean(0) - clean.xyz[[23, 24], :2].mean(0))
        noisy = [
            CaptureNoise(1.0, 0.0).apply(clean.xyz, clean.visibility, 16 / 9, rng)[0]
            for _ in range(200)
        ]
        err = np.std(np.stack(noisy)[:, [11, 12, 23, 24], 1] - clean.xyz[[11, 12, 23, 24], 1])
        spread.append(err / torso)  # torso lengths, as the capture model measures
    assert 0.005 < spread[0] < spread[1]  # a smaller person jitters more, in torso lengths
    off = CaptureNoise(0.0, 0.0)
    x = np.zeros((33, 3))
    assert off.apply(x, np.ones(33), 1.0, rng)[0] is x
    with pytest.raises(ValueError, match=r"jitter must lie in 0\.\.8"):
        CaptureNoise(jitter=9.0)


def test_scene_file_bystander_needs_its_path() -> None:
    with pytest.raises(ValueError, match="needs `to`"):
        build_scene(SceneConfig(bystanders=[BystanderConfig(behaviour="walk")]), "x")
