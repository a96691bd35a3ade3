; TF5200 diagnosis, ID 20685 "Dwell time programmed with additional axes.": the wrong program (a warning: processing continues)
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/252216715.html
; adapted: the page's ":" line dropped.
; expect: warning 20685
; expect: dwell N20 2 s
N10 G00 X0 Y0 Z0
N20 G04 X2 Y3
N1000 M30
