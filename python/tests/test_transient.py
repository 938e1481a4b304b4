"""A transient recording (``tmrotor transient``) read by the package, against the official
MCAP readers and the recording's own settings."""

from __future__ import annotations

from pathlib import Path

import tmrotor


def test_revolutions_and_samples_are_read(transient_rec: Path) -> None:
    rec = tmrotor.read(transient_rec)
    assert rec.info["complete"]
    assert rec.transient_info is not None
    assert rec.transient_info["profile"] == "fixed speed 400 rad/s"
    rev = rec.revolutions
    assert list(rev["revolution"]) == list(range(1, len(rev) + 1))
    assert len(rev) == 19
    assert (rev["omega_rad_s"] == 400.0).all()
    assert (rev["time_s"].diff().dropna() > 0).all()
    assert "amp_rms_node14_m" in rev.columns and "tnode1_c" in rev.columns
    assert rev["amp_rms_node14_m"].iloc[-1] > 0
    # the samples: 16 a revolution (the default), increasing in time
    s = rec.samples
    assert len(s) >= 16 * 18
    assert (s["time_s"].diff().dropna() > 0).all()


def test_revolutions_agree_with_the_official_readers(transient_rec: Path) -> None:
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    with open(transient_rec, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        official = [
            m
            for _, _, _, m in reader.iter_decoded_messages(topics=["/transient/revolution"])
        ]
    rev = tmrotor.read(transient_rec).revolutions
    assert len(official) == len(rev)
    for m, (_, row) in zip(official, rev.iterrows()):
        assert m.index == row["revolution"]
        assert m.amplitude_rms_m[13] == row["amp_rms_node14_m"]


def test_a_sweep_has_no_revolutions(sweep_rec: Path) -> None:
    rec = tmrotor.read(sweep_rec)
    assert rec.transient_info is None
    assert rec.revolutions.empty
