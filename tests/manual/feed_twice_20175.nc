; TF5200 diagnosis, ID 20175 "Double-programmed F-word.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250998155.html
; adapted: the page's ":" line dropped; M30 appended.
; expect: error 20175
N10 G00 X0 Y0 Z0
N20 F100 G01 X100 F200
N30 M30
