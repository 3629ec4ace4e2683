"""A disk that stays full: the run fails on one line naming ENOSPC, leaves metadata --resume
reads, a resume on the still-full disk refuses on one line, and once there is room the resume
carries on, keeps the first failure in metadata.yaml, names the movements the full disk lost
and says how to make the cut recording whole.

The full disk is a small tmpfs mounted over the runs folder in a mount namespace of the test's
own (unshare; as root, or in a user namespace), which only the run's processes see."""

from __future__ import annotations

import os
import shutil
import subprocess

import pytest
import yaml

from tests.conftest import REPO

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")


def _namespace() -> list[str]:
    for argv in (["unshare", "--user", "--map-root-user", "--mount"], ["unshare", "--mount"]):
        if shutil.which("unshare") and subprocess.run([*argv, "true"],
                                                      capture_output=True).returncode == 0:
            return argv
    pytest.fail("no mount namespace for a full disk: unshare failed (needs user namespaces, "
                "or root)")


def test_a_full_disk_is_a_clean_failure_and_resume_waits_for_room(tmp_path, ros_domain):
    runs, out = tmp_path / "runs", tmp_path / "out"
    runs.mkdir()
    out.mkdir()
    script = f"""
set -u
mount -t tmpfs -o size=120k tmpfs {runs}
{RUN} random --movements 400 --eval-every 0 --runs-dir {runs} --name full --quiet \\
    --domain {ros_domain} > {out}/first.txt 2>&1; echo $? > {out}/first.code
{RUN} --resume {runs}/full --quiet --domain {ros_domain} > {out}/second.txt 2>&1
echo $? > {out}/second.code
cp -a {runs}/full {out}/full
"""
    subprocess.run([*_namespace(), "sh", "-c", script], timeout=600, check=True,
                   env=dict(os.environ))
    first = (out / "first.txt").read_text()
    assert (out / "first.code").read_text().strip() == "1", first
    assert "Traceback" not in first, first
    last = first.strip().splitlines()[-1]
    assert last.startswith("run_experiment: failed: the recorder could not write the bag")
    assert "ENOSPC" in last and "metadata.yaml could not be written" in last, last
    assert yaml.safe_load((out / "full" / "metadata.yaml").read_text())["outcome"] == "running"
    second = (out / "second.txt").read_text()
    assert (out / "second.code").read_text().strip() == "1", second
    assert second.strip().splitlines() == [
        f"run_experiment: failed: the disk holding {runs}/full is full (0 bytes free: No space "
        "left on device [ENOSPC]): make room, then --resume again"], second
    # Room again (the folder on the test's own disk): the resume finishes and says what ended
    # the first part, which movements the full disk lost and that its recording is cut.
    import warnings

    from sgim_nodes.bag.resume import load_run_folder
    from sgim_nodes.graph.run_folder import read_claim

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        recorded = max(m.index for m in load_run_folder(out / "full").movements)
    segment, made = read_claim(out / "full")
    assert segment == "bag" and made > recorded, (made, recorded)  # made, then lost
    done = subprocess.run([RUN, "--resume", str(out / "full"), "--quiet", "--domain",
                           str(ros_domain)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert "its disk was full" in done.stderr
    meta = yaml.safe_load((out / "full" / "metadata.yaml").read_text())
    assert meta["outcome"] == "finished" and meta["movements_done"] == 400
    assert "No space left on device" in meta["resumed"][0]["previous_end"]
    assert meta["resumed"][0]["lost_movements"] == [recorded + 1, made]
    assert f"movements {recorded + 1}..{made} were lost" in done.stderr
    assert meta["resumed"][0]["cut_recordings"] == ["bag"]
    assert "ros2run.sh sgim_nodes repair" in done.stderr
