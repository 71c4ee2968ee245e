"""The rig's built-in control laws, the four strategies (``control.strategy``), as a controller on
the plug-in interface.

* :mod:`.kernel` - the strategies' compiled kernel ``kernel(t, obs, params, state, out)``, the
  signature a compiled plug-in implements: the loop calls it through a function pointer as it
  calls a plug-in;
* :mod:`.fuzzy` - the fuzzy law (FLC, Sec. 3-2, Eq. 14-37), one call per axis; :mod:`.fuzzy_surface`
  its control surface (analysis);
* :mod:`.smc` - the sliding-mode attitude law (Sec. 3-1, Eq. 5-13) and the switching function the
  sliding-mode position loop uses;
* :mod:`.pid` - the PID of the cascaded ``pid`` baseline;
* :mod:`.strategies` - which law runs which loop for each strategy name.

The stages the kernel runs (position law -> reference filter -> attitude law) are
:mod:`rig_emulator.control.controller`, the rig's own: a plug-in that replaces one loop gets them
for the other (:mod:`rig_emulator.control.plugin_step`). The ``pid`` strategy
written against the plug-in interface alone is :mod:`rig_emulator.controllers.examples.pid`.
Compiled code: this folder keys the compiled-code cache (``rig_emulator/_jit.py``).
"""
