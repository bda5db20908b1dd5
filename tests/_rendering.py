"""Whether off-screen rendering works here: a subprocess smoke test of pyvista (VTK
segfaults instead of raising when it is missing), shared by the viewer's, the command
line's and the notebooks' tests."""

_SMOKE = ("from meshladar.viz import viewer; pv = viewer._pyvista(); "
          "p = pv.Plotter(off_screen=True, window_size=(64, 48)); p.add_mesh(pv.Sphere()); "
          "img = p.screenshot(return_img=True); assert img.shape == (48, 64, 3)")
