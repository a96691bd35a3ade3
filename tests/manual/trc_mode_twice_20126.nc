; TF5200 diagnosis, ID 20126 "Double programmed selection mode of tool radius compensation.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250867595.html
; adapted: the page's ":" line dropped, N1000 M30 appended.
; expect: error 20126
N10 G00 X0 Y0 Z0
N20 G138 G41 G139
N1000 M30
