; TF5200 diagnosis, ID 20133 "Plane selection not allowed during active tool radius compensation.": the correct program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250893707.html
; adapted: the page's ":" lines dropped, N1000 M30 of the wrong program appended.
; expect: end X=0 Y=0 Z=0
; expect: blocks N10 N20 N25 N30 N35 N999 N1000
N10 G00 X0 Y0 Z0
N20 G41
N25 G40
N30 G19
N35 G41
N999 G40
N1000 M30
