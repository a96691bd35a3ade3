; TF5200 programming manual, "Counting loop ($FOR)": loop not executed
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206929163.html
; adapted: the loop body of the page's first example; N90 G01 F6000 added; M30 appended.
; expect: runs N110 0
; expect: end X=0 Y=0
N90 G01 F6000
N100 $FOR P1= 100, 10, 1  (start value above the end value with a positive increment: no pass)
N110 X SIN [P1 * 5]
N120 Y COS [P1 * 5]
N150 $ENDFOR
N160 M30
