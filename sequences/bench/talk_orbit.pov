// The talk's scene (sequences/talk.yaml) for POV-Ray 3.7, orbiting as in `rayreel bench`'s
// 24-frame 640x360 comparison: three spheres on the giant floor sphere, one point light at
// (5, 5, 5), reflection 0.5, max trace level 3, no antialiasing. POV-Ray is left-handed, so
// every z is negated. Reproduce the POV-Ray side with:
//   povray +Isequences/bench/talk_orbit.pov +W640 +H360 +KFI0 +KFF23 -A +WT2 -D +O/tmp/pov/frame.png
#version 3.7;
global_settings { max_trace_level 3 assumed_gamma 1.0 ambient_light rgb 1 }

#declare A = frame_number / 24 * 2 * pi;
camera {
  perspective
  location <-0.1 + 1.6 * sin(A), 0.35, 0.6 - 1.6 * cos(A)>
  look_at <-0.1, -0.1, 0.6>
  right x * 16 / 9
  angle 90
}
light_source { <5, 5, -5> color rgb 1 }

#macro Talk(Ambient, Diffuse)
  texture {
    pigment { color rgb Diffuse }
    finish { ambient Ambient diffuse 1 specular 1 roughness 1 / 100 reflection 0.5 }
  }
#end
sphere { <-0.2, 0, 1>, 0.7 Talk(<0.1, 0, 0>, <0.7, 0, 0>) }
sphere { <0.1, -0.3, 0>, 0.1 Talk(<0.1, 0, 0.1>, <0.7, 0, 0.7>) }
sphere { <-0.3, 0, 0>, 0.15 Talk(<0, 0.1, 0>, <0, 0.6, 0>) }
sphere { <0, -9000, 0>, 9000 - 0.7 Talk(<0.1, 0.1, 0.1>, <0.6, 0.6, 0.6>) }
