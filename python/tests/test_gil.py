"""World.step releases the GIL: a Python thread keeps running while the cape steps."""
import threading
import time

import capecloth


def test_a_python_thread_runs_while_step_runs():
    world = capecloth.World()
    human = world.add_humanoid(gait="sprint-turn")
    settings = capecloth.CapeSettings()
    settings.self_collision = True
    settings.sleep_speed = 0.0
    cape = human.attach_cape(resolution=32, settings=settings)
    human.advance_to(1 / 60)
    stamps = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            stamps.append(time.perf_counter())
            time.sleep(0.001)

    thread = threading.Thread(target=ticker)
    thread.start()
    time.sleep(0.02)
    # One step() call long enough to tell (at least 0.1 s whatever the machine's speed): twice the frames
    # until it is. The check is on what the thread did during the call, not on how long the call took.
    frames = 80
    while True:
        begin = time.perf_counter()
        world.step(frames=frames)
        end = time.perf_counter()
        if end - begin > 0.1 or frames >= 80 * 2**6:
            break
        frames *= 2
    stop.set()
    thread.join()
    during = [t for t in stamps if begin <= t <= end]
    step_time = end - begin
    gaps = [b - a for a, b in zip([begin] + during, during + [end])]
    print(f"step of {frames} frames {step_time * 1e3:.0f} ms, ticks during it {len(during)}, "
          f"largest gap {max(gaps) * 1e3:.1f} ms")
    assert step_time > 0.1, "the step is too short to tell"
    # Held, the GIL would leave the thread one gap as long as the whole step.
    assert max(gaps) < 0.25 * step_time
    assert len(during) > 0.1 * step_time / 0.0011
    after = cape.metrics()
    assert not after["blow_up"]
