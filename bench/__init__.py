"""PhotoDEM benchmarks: accuracy and speed side by side with peers, reported as ratios."""

#: Source of ``peak_mb()`` for the child processes that measure memory (prepended to their
#: code): the high-water mark of the process's own resident memory (``VmHWM``). Not
#: ``ru_maxrss``: Linux carries the parent's peak over fork + exec, so a child started by a
#: bench process that had grown to 10 GB reported 10 GB whatever it used itself.
PEAK_MB_SOURCE = r'''
def peak_mb():
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    import resource  # not Linux: the best there is
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
'''

exec(PEAK_MB_SOURCE)  # defines peak_mb() here too, for in-process use
