"""The bake record (store/record.py): its schema, its version, and the records of earlier bakes."""

import pytest

from sd_lighting.store.record import VERSION, BakeRecord, RecordError

ASKED = {"method": "prt_matrix", "light_order": 4, "visibility_order": 2, "rays": 256, "seed": 7,
         "lobe": "phong", "exponent": 8.0, "environment": "forest.exr", "refine": False,
         "refine_target": 0.02, "refine_max_vertices": 100000, "least_squares": True, "lightmap": 0,
         "shape": [1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0],
         "placement": [1.0, 0.0, 0.0, 3.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.5, 0.0, 0.0, 0.0, 1.0], "diffuse_lobe": True,
         "lobe_weights": False, "diffuse_share": 0.25}
FOUND = {"bake_id": "abc", "inputs": "def", "seconds": 1.5, "vertices": 10, "floats_per_vertex": 16,
         "bytes_per_vertex": 64, "refine_levels": 0, "unrefined_vertices": 10, "refine_seconds": 0.1,
         "refine_worst_left": 0.01, "refine_estimated_left": 0.005, "refine_budget_reached": False}


def test_a_record_round_trips_through_its_property_dict():
    record = BakeRecord.from_dict(dict(ASKED, **FOUND))
    stored = record.to_dict()
    assert stored["version"] == VERSION
    assert BakeRecord.from_dict(stored) == record
    assert "design_nodes_max" not in stored and "automatic" not in stored   # None: absent


def test_an_id_property_s_ints_read_as_the_field_types():
    """Blender keeps a bool as an int and a list as an IDPropertyArray (a sequence)."""
    record = BakeRecord.from_dict(dict(ASKED, least_squares=1, refine=0, exponent=8, shape=tuple(ASKED["shape"])))
    assert record.least_squares is True and record.refine is False
    assert isinstance(record.exponent, float) and record.shape[4] == 2.0


def test_settings_are_what_was_asked_and_chosen_without_what_was_found():
    chosen = dict(ASKED, automatic="cheapest within 5 %", per_pixel=True, predicted_error=0.03, frame_terms=99)
    record = BakeRecord.from_dict(dict(chosen, **FOUND))
    settings = record.settings()
    assert set(settings) == set(chosen)
    assert BakeRecord.from_dict(settings).settings() == settings   # a re-bake asks the same
    assert record.chosen_automatically and not BakeRecord.from_dict(ASKED).chosen_automatically


def test_records_before_the_version_read_as_version_1():
    record = BakeRecord.from_dict(dict(ASKED, **FOUND))
    assert record.refined and not record.has_texels and record.design_nodes_max is None


def test_records_before_the_two_lobe_shading_have_one_lobe():
    old = {k: v for k, v in ASKED.items() if k not in ("diffuse_lobe", "lobe_weights", "diffuse_share")}
    lobes = BakeRecord.from_dict(old).lobes
    assert (lobes.lobe, lobes.exponent, lobes.diffuse, lobes.weighted) == ("phong", 8.0, False, False)


def test_a_later_version_asks_to_bake_again():
    with pytest.raises(RecordError, match="later SD Lighting.*bake again"):
        BakeRecord.from_dict(dict(ASKED, version=VERSION + 1))


def test_a_missing_field_asks_to_bake_again():
    with pytest.raises(RecordError, match="no 'rays': bake again"):
        BakeRecord.from_dict({k: v for k, v in ASKED.items() if k != "rays"})
