"""The frequencies in a signal sampled in time (a tip coordinate of a dynamic run): the peaks of
its Hann-windowed, zero-padded spectrum, refined by a parabola through the log-magnitudes of a
peak and its two neighbours (accurate to a small fraction of a bin for well-separated modes)."""
import numpy as np


def dominant_frequencies(t, y, count=2, padding=8, separation=6):
    """The ``count`` strongest frequencies [Hz] in ``y`` sampled at the equally spaced times
    ``t`` [s] (mean removed), in increasing order, at least ``separation`` bins of the
    unpadded spectrum apart (closer peaks are a stronger one's sidelobes). ``padding``:
    zero-padding factor."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    step = float(np.mean(np.diff(t)))
    samples = (y - y.mean()) * np.hanning(y.size)
    size = padding * y.size
    magnitude = np.abs(np.fft.rfft(samples, n=size))
    log = np.log(magnitude + 1e-300)
    peaks = [k for k in range(1, magnitude.size - 1) if magnitude[k] >= magnitude[k - 1] and magnitude[k] > magnitude[k + 1]]
    strongest = []                     # a peak counts if it is not a stronger one's sidelobe
    for k in sorted(peaks, key=lambda k: magnitude[k], reverse=True):
        if all(abs(k - j) > separation * padding for j in strongest):
            strongest.append(k)
        if len(strongest) == count:
            break
    frequencies = []
    for k in strongest:
        a, b, c = log[k - 1], log[k], log[k + 1]
        shift = 0.5 * (a - c) / (a - 2 * b + c)
        frequencies.append((k + shift) / (size * step))
    return sorted(frequencies)
