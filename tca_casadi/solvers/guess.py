"""Initial guesses of the collocation NLP: the reference (unloaded) shape
(:mod:`tca_casadi.model.kinematics`) at the NLP's nodes."""
import numpy as np

from ..model.kinematics import reference_chain


def reference_guess(nlp, params):
    """Scaled NLP variables of the reference shape from the base pose in ``params``; F = 0."""
    robot = nlp.robot
    w = np.zeros(nlp.scale.size)
    samples = [nlp.node_s(m).ravel() for m in range(len(robot.modules))]
    for m, states in enumerate(reference_chain(robot, params, samples)):
        deviation = states - nlp.state_offset[m][:, None]
        w[nlp.state_index[m].transpose(1, 0, 2).reshape(13, -1)] = deviation
    w = w / nlp.scale
    partial_index = np.concatenate(nlp.partial_index) if nlp.partial_index else np.zeros(0, int)
    w[partial_index] = np.array(nlp.partials(w, params)).ravel()
    return w
