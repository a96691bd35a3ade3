; TF5200 diagnosis, ID 20114 "Double programmed selection of tool radius compensation.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250815371.html
; adapted: the page's ":" line dropped.
; expect: error 20114
N10 G00 X0 Y0 Z0
N20 G41 X10 Y20 G42
N1000 M30
