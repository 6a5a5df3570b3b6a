"""Measurement models: sampling, white noise, quantization, dropouts. Not a physical effect.

Every random draw comes from an explicit, seeded ``numpy.random.Generator``; the same scene and
seed give the same samples. Angles (channels in rad) get white noise ``noise_rad`` and are then
quantized to ``quantization_rad`` (an encoder); spin channels get ``spin_noise_rad_s``; a fraction
``dropout_fraction`` of samples is lost (NaN) on every channel.
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SensorModel:
    """Measurement model applied to simulated channels.

    Parameters
    ----------
    noise_rad : float
        Standard deviation of white noise on angle channels, rad.
    quantization_rad : float
        Encoder resolution, rad (0: none). Quantization adds variance q²/12.
    spin_noise_rad_s : float
        Standard deviation of white noise on spin-rate channels, rad/s.
    dropout_fraction : float
        Fraction of samples replaced by NaN.
    """

    noise_rad: float = 1.0e-4
    quantization_rad: float = 0.0
    spin_noise_rad_s: float = 0.0
    dropout_fraction: float = 0.0

    @classmethod
    def from_scene(cls, scene) -> "SensorModel":
        return cls(**dict(scene.sensor)) if scene.sensor else cls()

    def effective_sigma_rad(self) -> float:
        """Noise standard deviation including quantization, √(σ² + q²/12)."""
        return float(np.sqrt(self.noise_rad ** 2 + self.quantization_rad ** 2 / 12.0))

    def measure_angle(self, values, rng) -> np.ndarray:
        """Noisy, quantized angle samples (rad)."""
        y = np.asarray(values, dtype=float) + rng.normal(0.0, self.noise_rad, np.shape(values)) \
            if self.noise_rad else np.array(values, dtype=float)
        if self.quantization_rad:
            y = np.round(y / self.quantization_rad) * self.quantization_rad
        return self._drop(y, rng)

    def measure_rate(self, values, rng) -> np.ndarray:
        """Noisy spin-rate samples (rad/s)."""
        y = np.array(values, dtype=float)
        if self.spin_noise_rad_s:
            y = y + rng.normal(0.0, self.spin_noise_rad_s, y.shape)
        return self._drop(y, rng)

    def _drop(self, y, rng):
        if self.dropout_fraction:
            y = y.copy()
            y[rng.random(y.shape) < self.dropout_fraction] = np.nan
        return y


def scene_rng(seed, stream) -> np.random.Generator:
    """Independent, reproducible generator per (seed, stream name)."""
    key = [int(seed)] + [ord(c) for c in stream]
    return np.random.default_rng(np.random.SeedSequence(key))
